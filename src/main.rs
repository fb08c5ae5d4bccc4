//! The `sensorlight` command line. Errors print one clear message and exit non-zero; with
//! `SENSORLIGHT_VALIDATION=1` any validation-layer message also makes the exit code non-zero. A closed
//! standard output (`| head`) ends the program quietly with exit code 0 (see `output::stdout`).

mod cli;

use std::process::ExitCode;

use clap::Parser;
use sensorlight::output::stdout;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(code) => code,
        Err(e) if stdout::is_closed(&e) => ExitCode::SUCCESS,
        Err(e) => {
            sensorlight::errln!("error: {}", sensorlight::errors::message(&e));
            ExitCode::FAILURE
        }
    }
}
