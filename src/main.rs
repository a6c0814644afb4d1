//! The `odocal` command line: parses arguments and runs the command.
//! Exit codes: 0 success, 2 bad input or arguments, 1 any other failure.

mod cli;

use clap::Parser;
use odocal::pipeline::PipelineError;
use std::process::ExitCode;

fn main() -> ExitCode {
    let parsed = match cli::args::Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            // clap: help/version are success, everything else is a bad argument.
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    match cli::run(parsed.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("odocal: {e:#}");
            let code = e
                .downcast_ref::<PipelineError>()
                .map(|p| p.exit_code())
                .unwrap_or(1);
            ExitCode::from(code as u8)
        }
    }
}
