//! Prints the paper's task tables (Poubel Table I) as markdown; this is how
//! `src/imitation/phase/tables/table1.md` is generated.

use taskstack::imitation::phase::tables::TaskTables;
use taskstack::robots::nao;

fn main() -> std::io::Result<()> {
    let text = TaskTables::paper(&nao::profile()).to_string();
    // A reader that closed the pipe (`| head`) is not an error of ours.
    match std::io::Write::write_all(&mut std::io::stdout(), text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e),
        _ => Ok(()),
    }
}
