//! orbitlash command line: parse → load scenario → run → report. The outcome maps to
//! the exit status here and only here: 0 pass, 1 a verdict failed, 2 error.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::dispatch(args) {
        Ok(cli::Outcome::Pass) => ExitCode::SUCCESS,
        Ok(cli::Outcome::Fail) => ExitCode::from(1),
        Err(e) => {
            // a path or value quoted in the message is printed with its control
            // characters escaped (an escape sequence would act on the terminal)
            let chain = cli::error_chain(&e);
            eprintln!(
                "error: {}",
                orbitlash::units::shown_keeping(&chain, &['\n'])
            );
            ExitCode::from(2)
        }
    }
}
