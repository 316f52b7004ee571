//! `taskstack`: the command-line tool of the taskstack crate. Imitates motion clips with a
//! humanoid (one clip or a batch), solves benchmark problems, computes forward kinematics, and
//! writes a 3D viewer of every run. `taskstack --help` and `taskstack help COMMAND` explain
//! every option.

mod batch;
mod check;
mod contacts;
mod fk;
mod imitate;
mod live;
mod live_view;
mod options;
mod plots;
mod run;
mod solve;
mod stream;
mod svg;
mod view;
mod walk;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Prioritized task-stack inverse kinematics and online human-to-humanoid motion imitation.
///
/// Units everywhere: metres, radians, seconds. World axes: x forward, y left, z up.
#[derive(Debug, Parser)]
#[command(name = "taskstack", version, propagate_version = true)]
struct Cli {
    /// Print nothing but errors: no progress bar, no summary.
    #[arg(long, short, global = true)]
    quiet: bool,
    /// Print the result on stdout as one JSON document (for scripts) instead of the summary.
    #[arg(long, global = true)]
    json: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Imitate(imitate::ImitateArgs),
    Batch(batch::BatchArgs),
    Check(check::CheckArgs),
    Contacts(contacts::ContactsArgs),
    Fk(fk::FkArgs),
    Live(live::LiveArgs),
    Solve(solve::SolveArgs),
    Stream(stream::StreamArgs),
    View(view::ViewArgs),
    Walk(walk::WalkArgs),
}

/// How the command reports: progress and summary for people, JSON for scripts, or nothing.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Report {
    pub(crate) quiet: bool,
    pub(crate) json: bool,
}

impl Report {
    /// Whether to show progress bars and human summaries.
    pub(crate) fn human(self) -> bool {
        !self.quiet && !self.json
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let report = Report {
        quiet: cli.quiet,
        json: cli.json,
    };
    let result = match cli.command {
        Command::Imitate(args) => imitate::run(args, report),
        Command::Batch(args) => batch::run(args, report),
        Command::Check(args) => check::run(args, report),
        Command::Contacts(args) => contacts::run(args, report),
        // fk's output is its JSON lines: nothing for --quiet to silence or --json to change.
        Command::Fk(_) if cli.quiet || cli.json => {
            eprintln!(
                "taskstack: error: fk always writes JSON lines; --quiet and --json do not apply"
            );
            return ExitCode::from(2);
        }
        Command::Fk(args) => fk::run(args),
        Command::Live(args) => live::run(args, report),
        Command::Solve(args) => solve::run(args, report),
        Command::Stream(args) => stream::run(args, report),
        Command::View(args) => view::run(args, report),
        Command::Walk(args) => walk::run(args, report),
    };
    match result {
        Ok(code) => code,
        Err(error) if is_broken_pipe(&error) => ExitCode::SUCCESS,
        Err(error) if error.is::<options::UsageError>() => {
            eprintln!("taskstack: error: {error}");
            ExitCode::from(2)
        }
        Err(error) => {
            eprintln!("taskstack: error: {}", describe(&error));
            ExitCode::FAILURE
        }
    }
}

/// `error` and its causes, `: `-separated, each cause once: our errors' messages already quote
/// their source's, which `{:#}` would print a second time.
pub(crate) fn describe(error: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in error.chain() {
        let message = cause.to_string();
        if !text.contains(&message) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&message);
        }
    }
    text
}

/// Writes `text` to stdout. A reader that went away (`taskstack … | head`) gives an error that
/// `main` treats as success, instead of the panic of `println!`.
pub(crate) fn output(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(text.as_bytes())?;
    stdout.flush()?;
    Ok(())
}

/// A reader of our stdout went away (`taskstack … | head`): not an error of ours.
fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
