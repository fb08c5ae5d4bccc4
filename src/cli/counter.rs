//! Progress of work counted in equal units (a reference's rows, the metrics' renders, a benchmark's
//! rounds), shown as a render's is (`progress`): a bar on a terminal; elsewhere (a log) a plain line every
//! tenth of the work or every [`LINE_EVERY`], whichever comes first; nothing with `-q`.

use std::io::IsTerminal as _;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

use super::progress::{LINE_EVERY, duration};
use super::say;

pub struct Counter {
    total: u64,
    unit: &'static str,
    done: AtomicU64,
    start: Instant,
    bar: Option<ProgressBar>,
    /// On a log: when the last line was written, and the tenths of the work it had reported.
    lines: Option<Mutex<(Instant, u64)>>,
}

impl Counter {
    pub fn new(total: u64, unit: &'static str) -> Self {
        let (show, terminal) = (say::normal(), std::io::stderr().is_terminal());
        let bar = (show && terminal).then(|| {
            let bar = ProgressBar::new(total);
            let template = format!("{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {unit} ({{eta}} left)");
            let style = ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style.progress_chars("=> "));
            bar
        });
        let start = Instant::now();
        let lines = (show && !terminal).then(|| Mutex::new((start, 0)));
        Self { total, unit, done: AtomicU64::new(0), start, bar, lines }
    }

    /// `n` more units are done.
    pub fn inc(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        if let Some(bar) = &self.bar {
            bar.inc(n);
        }
        let Some(lines) = &self.lines else { return };
        let mut last = lines.lock().unwrap_or_else(|e| e.into_inner());
        let tenths = (10 * done).checked_div(self.total).unwrap_or(10);
        if tenths > last.1 || last.0.elapsed() >= LINE_EVERY {
            sensorlight::errln!("{}", self.line(done));
            *last = (Instant::now(), tenths);
        }
    }

    /// `[  12.3 s] 30/96 rows (31 %), 26 s left`: the time left at the rate so far.
    fn line(&self, done: u64) -> String {
        let elapsed = self.start.elapsed().as_secs_f64();
        let percent = 100.0 * done as f64 / self.total.max(1) as f64;
        let mut line = format!("[{elapsed:6.1} s] {done}/{} {} ({percent:.0} %)", self.total, self.unit);
        if done > 0 && done < self.total {
            line += &format!(", {} left", duration(elapsed * (self.total - done) as f64 / done as f64));
        }
        line
    }

    /// Runs `f` (which writes lines of its own) with the bar out of the way.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        match &self.bar {
            Some(bar) => bar.suspend(f),
            None => f(),
        }
    }

    /// Ends the display, leaving nothing of the bar on the terminal.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl Drop for Counter {
    fn drop(&mut self) {
        self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_says_the_share_done_and_the_time_left_at_the_rate_so_far() {
        let mut counter = Counter::new(40, "rows");
        counter.start = Instant::now() - std::time::Duration::from_secs(10);
        let line = counter.line(10);
        assert!(line.ends_with("10/40 rows (25 %), 30 s left"), "{line}");
        assert!(counter.line(40).ends_with("40/40 rows (100 %)"), "{}", counter.line(40));
    }
}
