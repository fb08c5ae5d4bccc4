//! Results printed on standard output, and diagnostics on standard error. A reader that stops reading (`sensorlight devices | head -1`) is not
//! a failure of ours: a write to the closed pipe returns [`StdoutClosed`], which ends the program quietly with
//! exit code 0, as if all had been read (the main function checks with [`is_closed`]). Any other error
//! writing standard output (a full disk behind `>`) is an error like any other.

use std::io::Write as _;

/// The reader of standard output has gone.
#[derive(Debug, thiserror::Error)]
#[error("standard output was closed")]
pub struct StdoutClosed;

/// Writes one line to standard output, flushed.
pub fn line(args: std::fmt::Arguments<'_>) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match writeln!(out, "{args}").and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(StdoutClosed.into()),
        Err(e) => Err(anyhow::Error::new(e).context("cannot write to standard output")),
    }
}

/// Whether `error` is, or was caused by, standard output having been closed.
pub fn is_closed(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| cause.is::<StdoutClosed>())
}

/// `println!` that returns an error instead of panicking when standard output is closed:
/// `outln!("{x}")?`.
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::output::stdout::line(format_args!($($arg)*))
    };
}

/// Writes one line of diagnostics to standard error. They are best effort: with standard error closed
/// (`sensorlight render … 2>&1 | head -1`) the work goes on and its outputs are written; `eprintln!` would
/// panic instead.
pub fn diagnostic(args: std::fmt::Arguments<'_>) {
    let _ = writeln!(std::io::stderr().lock(), "{args}");
}

/// `eprintln!` that never panics: see [`diagnostic`].
#[macro_export]
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::output::stdout::diagnostic(format_args!($($arg)*))
    };
}
