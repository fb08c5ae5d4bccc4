//! The `sensorlight` command line. Errors print one clear message and exit non-zero; with
//! `SENSORLIGHT_VALIDATION=1` any validation-layer message also makes the exit code non-zero.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
