//! The `sensorlight` command line. Errors print one clear message and exit non-zero; with
//! `SENSORLIGHT_VALIDATION=1` any validation-layer message also makes the exit code non-zero. A closed
//! standard output (`| head`) ends the program quietly with exit code 0 (see `output::stdout`). A render
//! stopped by SIGINT or SIGTERM says "interrupted" and exits 130 or 143 (see `sensorlight::cancel`).

mod cli;

use std::process::ExitCode;

use clap::Parser;
use sensorlight::cancel::Cancelled;
use sensorlight::output::stdout;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(code) => code,
        Err(e) if stdout::is_closed(&e) => ExitCode::SUCCESS,
        // Stopped by a signal: said once, and the shell's code for it (130 for SIGINT, 143 for SIGTERM).
        Err(e) if e.is::<Cancelled>() => {
            sensorlight::errln!("interrupted");
            e.downcast_ref::<Cancelled>().map_or(ExitCode::FAILURE, |Cancelled(r)| ExitCode::from(r.exit_code()))
        }
        Err(e) => {
            sensorlight::errln!("error: {}", sensorlight::errors::message(&e));
            ExitCode::FAILURE
        }
    }
}
