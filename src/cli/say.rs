//! How much the program says on standard error. `-q`: errors only. Default: warnings, progress, what was
//! written and a one-line summary. `-v`: also the device and strategy details (self-checks, `auto`'s
//! measurements) and per-round statistics. Results on standard output are never affected.

use std::sync::atomic::{AtomicU8, Ordering};

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verbosity {
    Quiet,
    Normal,
    Verbose,
}

static LEVEL: AtomicU8 = AtomicU8::new(Verbosity::Normal as u8);

pub fn set(level: Verbosity) {
    LEVEL.store(level as u8, Ordering::Relaxed);
}

pub fn level() -> Verbosity {
    match LEVEL.load(Ordering::Relaxed) {
        0 => Verbosity::Quiet,
        1 => Verbosity::Normal,
        _ => Verbosity::Verbose,
    }
}

/// Not `-q`.
pub fn normal() -> bool {
    level() >= Verbosity::Normal
}

/// `-v`.
pub fn verbose() -> bool {
    level() >= Verbosity::Verbose
}
