//! The `talus` command line: parse, run, and exit 0 on success, 2 on any error (with a message that says what is
//! wrong and how to fix it).

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    match cli::main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
