//! The render's progress as the window shows it (the title, each round's picture), and the script's `sync`.

use std::cell::RefCell;
use std::io::{BufRead as _, Write as _};
use std::time::Duration;

use super::Session;
use crate::cancel::Reason;
use crate::renderer::{BounceDone, Phase, Progress, RoundDone, Snapshot};

/// Prints `line` on standard output and waits for a line on standard input (a test's turn to look).
pub(super) fn wait_for_stdin(line: &str) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{line}");
    let _ = out.flush();
    let mut answer = String::new();
    let _ = std::io::stdin().lock().read_line(&mut answer);
}

/// The render's progress, seen by the window: every snapshot presented, the events read before each batch.
pub(super) struct ViewProgress<'s, 'h>(pub(super) RefCell<&'s mut Session<'h>>);

impl Progress for ViewProgress<'_, '_> {
    fn phase(&self, phase: Phase) {
        let mut s = self.0.borrow_mut();
        s.this.phase = phase;
        s.title(true);
    }

    fn done(&self, n: u64) {
        let mut s = self.0.borrow_mut();
        s.this.sensors += n;
        s.title(false);
    }

    fn round(&self, round: &RoundDone) {
        let mut s = self.0.borrow_mut();
        s.this.resolved = round.resolved_pixels as f64 / round.pixels.max(1) as f64;
    }

    fn bounce(&self, bounce: &BounceDone) {
        self.0.borrow_mut().this.bounce = bounce.bounce;
    }

    fn wants_snapshot(&self, _round: u32) -> bool {
        true
    }

    fn snapshot(&self, snapshot: &Snapshot) {
        let mut s = self.0.borrow_mut();
        s.this.preview = Some(snapshot.image.clone());
        s.this.rounds = snapshot.round;
        s.title(true);
        s.present();
    }

    fn cancelled(&self) -> Option<Reason> {
        let mut s = self.0.borrow_mut();
        if let Some(reason) = s.host.interrupted() {
            return Some(reason);
        }
        s.pump(Some(Duration::ZERO));
        (s.wanted || s.quit || s.error.is_some()).then_some(Reason::Superseded)
    }
}
