//! Stopping a long computation part-way, cleanly: a flag set from outside (SIGINT, SIGTERM) and read by
//! the renderer between batches (docs/DESIGN.md §4). Work stops where it can stop whole: the batches in
//! flight are waited for, every object is dropped by its owner, and [`Cancelled`] travels up like any error,
//! so staged outputs and previews are removed on the way out.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Why the work was stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// SIGINT (Ctrl-C).
    Interrupt,
    /// SIGTERM.
    Terminate,
    /// Not wanted any more: the live viewer's camera moved, or its window closed. The viewer starts the next
    /// render or ends; this never reaches the shell.
    Superseded,
}

impl Reason {
    /// The number the flag stores: the signal's (the same on every Unix), or one no signal has.
    fn code(self) -> i32 {
        match self {
            Reason::Interrupt => 2,
            Reason::Terminate => 15,
            Reason::Superseded => 1000,
        }
    }

    /// The shell's exit status for a program ended by this signal: 128 + its number (130, 143); 1 for a
    /// render superseded.
    pub fn exit_code(self) -> u8 {
        match self {
            Reason::Superseded => 1,
            signal => 128 + signal.code() as u8,
        }
    }
}

/// The work was stopped before it was done; nothing it would have written was.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("interrupted")]
pub struct Cancelled(pub Reason);

/// A flag that says whether, and why, to stop. Clones share it.
#[derive(Clone, Debug, Default)]
pub struct Cancel {
    /// 0: go on; else the [`Reason::code`] of what asked to stop.
    signal: Arc<AtomicUsize>,
}

impl Cancel {
    /// A flag nothing sets but [`Cancel::cancel`].
    pub fn new() -> Self {
        Self::default()
    }

    /// A flag set by SIGINT and SIGTERM, which no longer end the process at once. A second of either, while
    /// the work is stopping, ends it at once with the signal's exit code, as a user pressing Ctrl-C twice
    /// expects (what it was writing is then left as it is).
    pub fn on_signals() -> std::io::Result<Self> {
        let cancel = Self::new();
        let armed = Arc::new(AtomicBool::new(false));
        for reason in [Reason::Interrupt, Reason::Terminate] {
            let signal = reason.code();
            // The shutdown first: it must see the flag as the previous signal left it.
            signal_hook::flag::register_conditional_shutdown(signal, reason.exit_code().into(), armed.clone())?;
            signal_hook::flag::register(signal, armed.clone())?;
            signal_hook::flag::register_usize(signal, cancel.signal.clone(), signal as usize)?;
        }
        Ok(cancel)
    }

    /// Asks the work to stop.
    pub fn cancel(&self, reason: Reason) {
        self.signal.store(reason.code() as usize, Ordering::SeqCst);
    }

    /// Whether, and why, the work should stop.
    pub fn reason(&self) -> Option<Reason> {
        match self.signal.load(Ordering::SeqCst) {
            0 => None,
            s if s == Reason::Terminate.code() as usize => Some(Reason::Terminate),
            s if s == Reason::Superseded.code() as usize => Some(Reason::Superseded),
            _ => Some(Reason::Interrupt),
        }
    }

    /// [`Cancelled`] if the work should stop.
    pub fn check(&self) -> Result<(), Cancelled> {
        self.reason().map_or(Ok(()), |r| Err(Cancelled(r)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cancel_is_seen_by_every_clone_with_its_reason() {
        let cancel = Cancel::new();
        let seen = cancel.clone();
        assert_eq!(seen.check(), Ok(()));
        cancel.cancel(Reason::Terminate);
        assert_eq!(seen.check(), Err(Cancelled(Reason::Terminate)));
        assert_eq!((Reason::Interrupt.exit_code(), Reason::Terminate.exit_code()), (130, 143));
        assert_eq!(Cancelled(Reason::Interrupt).to_string(), "interrupted");
    }
}
