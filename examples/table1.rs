//! Prints the paper's task tables (Poubel Table I) as markdown; this is how
//! `src/imitation/table1.md` is generated.

use taskstack::imitation::tables::TaskTables;
use taskstack::robots::nao;

fn main() {
    print!("{}", TaskTables::paper(&nao::profile()));
}
