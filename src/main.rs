//! The `volcache` command line: orchestration only (no physics lives here).

mod cli;

use clap::Parser;

fn main() -> std::process::ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(code) => code,
        // A computation stopped by Ctrl-C, wherever it was: 128 + SIGINT, as shells report it.
        Err(e) if e.chain().any(|c| c.is::<volcache::progress::Cancelled>()) => cli::cancelled().unwrap_or_else(|e| {
            eprintln!("error: {e:#}");
            std::process::ExitCode::from(2)
        }),
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::from(2)
        }
    }
}
