//! One progress display for a whole render: the strategy choice, the G-buffer, every refinement round and
//! the post passes. A render's total work is not known up front (each round decides the next), so the
//! measure is the share of pixels resolved, by sensing or by interpolation: it only grows, round by round,
//! and the bar never refills. Within a round it shows the round's sensors done and the sensing rate.
//!
//! On a terminal: a bar on standard error. Elsewhere (a log): a plain line every tenth of the pixels
//! resolved or every [`LINE_EVERY`], whichever comes first. Nothing with `-q`.
//!
//! Before the rounds, the radiance cache: the share of its entries sensed (its walk reaches at most all of
//! them), and once a second of it is timed, at most how long the rest takes; then its bounces. Rates are
//! the phase's sensors over the phase's own time.
//!
//! Once the first round's size and a cost per sensor are known (the strategy probe's measurement, else the
//! first sensors'), a run expected to take longer than [`ESTIMATE_ABOVE`] says so.

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use sensorlight::cancel::{Cancel, Reason};
use sensorlight::output::png;
use sensorlight::renderer::{BounceDone, Phase, Progress, RoundDone, Snapshot};

use super::say;

/// Rhythm of the plain lines when the pixels resolved do not move.
pub const LINE_EVERY: Duration = Duration::from_secs(5);
/// Runs expected to take longer than this are announced with their estimate.
pub const ESTIMATE_ABOVE: Duration = Duration::from_secs(10);
/// Sensors of a whole render over those of its first grid, on the shipped scenes with their defaults
/// (tile 16): door-ajar 35, small-light 42, cornell 67, cornell-mcguire 69, room 108. The refinement decides
/// the real count, so the estimate is said as this range, centred on [`SENSORS_TYPICAL`].
pub const SENSORS_OVER_FIRST_GRID: (f64, f64) = (35.0, 110.0);
pub const SENSORS_TYPICAL: f64 = 60.0;

/// The phase name of the radiance cache's bounces.
const BOUNCES: &str = "radiance cache";

/// What the bar counts: a render's pixels resolved (by sensing or interpolation, round by round), or a
/// bake's texels, each sensed once: their number is known up front, and so is the estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Measure {
    #[default]
    Pixels,
    Texels,
}

impl Measure {
    fn text(self) -> &'static str {
        match self {
            Self::Pixels => "of pixels resolved",
            Self::Texels => "of texels baked",
        }
    }
}

/// Where a render's previews go: `path` rewritten after every `every` rounds.
pub struct Preview {
    pub every: u32,
    pub path: PathBuf,
    pub exposure: f32,
}

pub struct RenderProgress {
    shared: Arc<Shared>,
    ticker: Option<(Sender<()>, JoinHandle<()>)>,
    preview: Option<Preview>,
    /// What the render asks before each batch: whether to stop.
    cancel: Cancel,
}

struct Shared {
    bar: Option<ProgressBar>,
    lines: bool,
    start: Instant,
    state: Mutex<State>,
}

#[derive(Default)]
struct State {
    phase: &'static str,
    measure: Measure,
    pixels: u64,
    resolved: u64,
    round: u32,
    /// The radiance cache (global illumination), before the rounds: its walk's level, and its last bounce.
    cache_level: Option<sensorlight::renderer::CacheLevel>,
    bounce: u32,
    round_queued: u64,
    round_done: u64,
    sensors_done: u64,
    /// When the phase began, and the sensors done in it: its rate.
    phase_start: Option<Instant>,
    phase_done: u64,
    last_line: Option<Instant>,
    /// Tenths of the pixels resolved already reported by a plain line.
    tenths_said: u64,
    /// The strategy probe's time per sensor, when it measured one this run.
    probe_per_sensor: Option<Duration>,
    first_grid: Option<u64>,
    /// When the first batch was done, and the sensors done then.
    first_batch: Option<(Instant, u64)>,
    estimated: bool,
}

impl RenderProgress {
    /// A display for a render of `pixels` pixels (0: no image, the radiance cache alone), starting with the
    /// strategy choice; the render stops between batches once `cancel` is set.
    pub fn new(pixels: u64, preview: Option<Preview>, cancel: Cancel) -> Self {
        Self::with_measure(pixels, Measure::Pixels, preview, cancel)
    }

    /// A display for a bake of `texels` texels.
    pub fn for_texels(texels: u64, cancel: Cancel) -> Self {
        Self::with_measure(texels, Measure::Texels, None, cancel)
    }

    fn with_measure(pixels: u64, measure: Measure, preview: Option<Preview>, cancel: Cancel) -> Self {
        let show = say::normal();
        let terminal = std::io::stderr().is_terminal();
        let bar = (show && terminal).then(|| {
            let bar = ProgressBar::new(pixels.max(1));
            // No pixels (`sensorlight cache`): the phase alone.
            let template = match pixels {
                0 => "{spinner} {elapsed:>4} {msg}".to_owned(),
                _ => format!("{{spinner}} {{elapsed:>4}} [{{bar:30}}] {{percent:>3}}% {} · {{msg}}", measure.text()),
            };
            let style = ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style.progress_chars("=> "));
            bar.enable_steady_tick(Duration::from_millis(200));
            bar
        });
        let lines = show && !terminal;
        let state = State { phase: "choosing the batching strategy", measure, pixels, ..State::default() };
        let shared = Arc::new(Shared { bar, lines, start: Instant::now(), state: Mutex::new(state) });
        shared.update(false);
        let ticker = lines.then(|| {
            let (stop, stopped) = mpsc::channel::<()>();
            let shared = shared.clone();
            let handle = std::thread::spawn(move || {
                while let Err(RecvTimeoutError::Timeout) = stopped.recv_timeout(LINE_EVERY) {
                    shared.update(false);
                }
            });
            (stop, handle)
        });
        Self { shared, ticker, preview, cancel }
    }

    /// Prints `text` above the bar (or as a line), when not `-q`.
    pub fn say(&self, text: &str) {
        if !say::normal() {
            return;
        }
        match &self.shared.bar {
            Some(bar) => bar.println(text),
            None => sensorlight::errln!("{text}"),
        }
    }

    /// The strategy probe measured `per_sensor` for the strategy chosen (at the render's sensor size).
    pub fn probe_measured(&self, per_sensor: Duration) {
        self.shared.lock().probe_per_sensor = Some(per_sensor);
    }

    /// Ends the display, leaving nothing of the bar on the terminal.
    pub fn finish(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        if let Some((stop, handle)) = self.ticker.take() {
            drop(stop);
            let _ = handle.join();
        }
        if let Some(bar) = &self.shared.bar {
            bar.finish_and_clear();
        }
    }
}

impl Drop for RenderProgress {
    fn drop(&mut self) {
        self.stop();
    }
}

impl Shared {
    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Refreshes the bar; on a log, writes a line if a tenth of the pixels was crossed, `force`d, or the
    /// last line is [`LINE_EVERY`] old.
    fn update(&self, force: bool) {
        let mut s = self.lock();
        // Over the phase's own time, once there is a second of it to measure.
        let elapsed = s.phase_start.map_or(0.0, |t| t.elapsed().as_secs_f64());
        let rate = (elapsed >= 1.0 && s.phase_done > 0).then(|| s.phase_done as f64 / elapsed);
        let mut what = s.phase.to_owned();
        if s.round > 0 && s.phase == "sensing" {
            what = match s.measure {
                Measure::Pixels => format!("round {}: {}/{} sensors", s.round, s.round_done, s.round_queued),
                Measure::Texels if s.round == 1 => format!("{}/{} texels", s.round_done, s.round_queued),
                Measure::Texels => format!("footprints: {}/{} points", s.round_done, s.round_queued),
            };
        }
        if let (Some(level), BOUNCES) = (s.cache_level, s.phase) {
            let sensed = level.reached - level.sensors + s.round_done.min(level.sensors);
            let share = 100.0 * sensed as f64 / level.entries.max(1) as f64;
            what = if s.bounce > 0 {
                format!("radiance cache: bounce {}", s.bounce + 1)
            } else {
                format!(
                    "radiance cache: {share:.0} % of its entries at most ({sensed} sensed, of {}; level {})",
                    level.entries, level.level
                )
            };
            if let Some(rate) = rate.filter(|_| s.bounce == 0) {
                what += &format!(", at most {} left", duration((level.entries - sensed) as f64 / rate));
            }
        }
        if let Some(rate) = rate {
            what += &format!(", {rate:.0} sensors/s");
            // A bake's pass: its points are known, so is the time left at the pass's own rate.
            if s.measure == Measure::Texels && s.phase == "sensing" && s.round_done < s.round_queued {
                what += &format!(", about {} left", duration((s.round_queued - s.round_done) as f64 / rate));
            }
        }
        if let Some(bar) = &self.bar {
            bar.set_position(s.resolved);
            bar.set_message(what);
            return;
        }
        if !self.lines {
            return;
        }
        let tenths = (10 * s.resolved).checked_div(s.pixels).unwrap_or(0);
        let due = s.last_line.is_none_or(|t| t.elapsed() >= LINE_EVERY);
        if force || tenths > s.tenths_said || due {
            let resolved = match s.pixels {
                0 => String::new(),
                n => format!("{:3.0} % {}; ", 100.0 * s.resolved as f64 / n as f64, s.measure.text()),
            };
            sensorlight::errln!("[{:6.1} s] {resolved}{what}", self.start.elapsed().as_secs_f64());
            s.tenths_said = tenths;
            s.last_line = Some(Instant::now());
        }
    }

    /// Says once how long the render should take, when that is long: expected sensors (the first grid's
    /// times [`SENSORS_OVER_FIRST_GRID`]) at the measured cost per sensor.
    fn estimate(&self) -> Option<String> {
        let mut s = self.lock();
        let first = s.first_grid?;
        if s.estimated {
            return None;
        }
        let (per_sensor, source) = match (s.probe_per_sensor, s.first_batch) {
            (Some(t), _) => (t.as_secs_f64(), "measured by the strategy probe"),
            // The rate over a second of sensing after the first batch (which also pays for pipelines warming
            // up and the light hints).
            (None, Some((t, n))) if t.elapsed() >= Duration::from_secs(1) && s.sensors_done > n => {
                (t.elapsed().as_secs_f64() / (s.sensors_done - n) as f64, "measured on the first sensors")
            }
            _ => return None,
        };
        s.estimated = true;
        if s.measure == Measure::Texels {
            // A bake's texels are known up front: the bar says how long is left as it goes.
            return None;
        }
        estimate_line(first, s.pixels, per_sensor, source)
    }
}

/// The estimate said for a render whose first grid senses `first` of its `pixels` at `per_sensor` seconds
/// each (`source`: how that was measured), when it is long ([`ESTIMATE_ABOVE`]). No pixel is sensed twice:
/// where the first grid is every pixel (`--tile 1`), or the range reaches them all, the pixels bound it.
fn estimate_line(first: u64, pixels: u64, per_sensor: f64, source: &str) -> Option<String> {
    let sensors = |ratio: f64| (first as f64 * ratio).min(pixels.max(first) as f64);
    let seconds = |ratio: f64| sensors(ratio) * per_sensor;
    let (low, high) = SENSORS_OVER_FIRST_GRID;
    let rate = format!("at {:.2} ms a sensor ({source})", per_sensor * 1e3);
    (seconds(SENSORS_TYPICAL) > ESTIMATE_ABOVE.as_secs_f64()).then(|| match sensors(low) < sensors(high) {
        true => format!(
            "estimate: {} to {} (~{:.0} sensors: the first grid's {first} × {low}–{high}, the shipped scenes' range, \
             at most the {pixels} pixels) {rate}",
            duration(seconds(low)),
            duration(seconds(high)),
            sensors(SENSORS_TYPICAL),
        ),
        false => format!("estimate: {} ({:.0} sensors: every pixel) {rate}", duration(seconds(low)), sensors(low)),
    })
}

/// `42 s`, `3 min 20 s`.
pub(super) fn duration(seconds: f64) -> String {
    if seconds < 60.0 {
        format!("{seconds:.0} s")
    } else {
        format!("{:.0} min {:.0} s", (seconds / 60.0).floor(), seconds % 60.0)
    }
}

impl Progress for RenderProgress {
    fn phase(&self, phase: Phase) {
        {
            let mut s = self.shared.lock();
            s.phase = match phase {
                Phase::GBuffer => "G-buffer",
                Phase::Bounces => BOUNCES,
                Phase::Sensing => "sensing",
                Phase::Post => "interpolation, filter, composition",
            };
            (s.phase_start, s.phase_done) = (Some(Instant::now()), 0);
        }
        self.shared.update(false);
    }

    fn queued(&self, n: u64) {
        {
            let mut s = self.shared.lock();
            (s.round_queued, s.round_done) = (n, 0);
            if s.phase != BOUNCES {
                s.round += 1;
                s.first_grid.get_or_insert(n);
                // A bake's later passes (texels taken over their footprint) add to what is to do.
                if s.measure == Measure::Texels && s.round > 1 {
                    s.pixels += n;
                    if let Some(bar) = &self.shared.bar {
                        bar.set_length(s.pixels);
                    }
                }
            }
        }
        if let Some(text) = self.shared.estimate() {
            self.say(&text);
        }
        self.shared.update(false);
    }

    fn done(&self, n: u64) {
        {
            let mut s = self.shared.lock();
            s.round_done += n;
            s.sensors_done += n;
            if s.measure == Measure::Texels && s.phase == "sensing" {
                s.resolved += n;
            }
            s.phase_done += n;
            let done = s.sensors_done;
            s.first_batch.get_or_insert((Instant::now(), done));
        }
        if let Some(text) = self.shared.estimate() {
            self.say(&text);
        }
        self.shared.update(false);
    }

    fn round(&self, round: &RoundDone) {
        self.shared.lock().resolved = round.resolved_pixels;
        if say::verbose() {
            let percent = 100.0 * round.resolved_pixels as f64 / round.pixels.max(1) as f64;
            self.say(&format!("round {}: {} sensors; {percent:.1} % of pixels resolved", round.round, round.sensors));
        }
        self.shared.update(false);
    }

    fn cache_level(&self, level: &sensorlight::renderer::CacheLevel) {
        self.shared.lock().cache_level = Some(*level);
        self.shared.update(false);
    }

    fn bounce(&self, bounce: &BounceDone) {
        self.shared.lock().bounce = bounce.bounce;
        self.shared.update(false);
        if say::verbose() {
            let change = bounce.change.map_or(String::new(), |c| format!(", the cache moved {:.2} %", 100.0 * c));
            match bounce.sensors {
                0 => self.say(&format!("bounce {}: products with the transport's rows{change}", bounce.bounce)),
                n => self.say(&format!("bounce {}: {n} cache sensors{change}", bounce.bounce)),
            }
        }
    }

    fn wants_snapshot(&self, round: u32) -> bool {
        self.preview.as_ref().is_some_and(|p| round.is_multiple_of(p.every))
    }

    fn cancelled(&self) -> Option<Reason> {
        self.cancel.reason()
    }

    fn snapshot(&self, snapshot: &Snapshot) {
        let Some(preview) = &self.preview else { return };
        let size = snapshot.size;
        // A preview that cannot be written costs the render nothing: said, not fatal.
        match png::write(&preview.path, size.width, size.height, &snapshot.image, preview.exposure) {
            Ok(()) if say::verbose() => {
                self.say(&format!("preview after round {}: {}", snapshot.round, preview.path.display()))
            }
            Ok(()) => {}
            Err(e) => self.say(&format!("warning: preview {}: {e:#}", preview.path.display())),
        }
    }
}

impl RenderProgress {
    /// The render is over: every pixel resolved.
    pub fn complete(&self) {
        {
            let mut s = self.shared.lock();
            s.resolved = s.pixels;
            s.phase = "done";
        }
        self.shared.update(true);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_estimate_counts_no_pixel_twice() {
        // `--tile 1` on 400 × 300: the first grid is every pixel, and so is the whole render.
        let every = estimate_line(120_000, 120_000, 1e-3, "measured").unwrap();
        assert!(every.starts_with("estimate: 2 min 0 s (120000 sensors: every pixel)"), "{every}");
        // Tile 16 on the same image: the shipped scenes' range, below the pixels.
        let range = estimate_line(480, 120_000, 1e-3, "measured").unwrap();
        assert!(range.starts_with("estimate: 17 s to 53 s (~28800 sensors"), "{range}");
        // A first grid whose range passes the pixels: its top stops there.
        let capped = estimate_line(2_000, 120_000, 1e-3, "measured").unwrap();
        assert!(capped.starts_with("estimate: 1 min 10 s to 2 min 0 s (~120000 sensors"), "{capped}");
        // Short renders say nothing.
        assert_eq!(estimate_line(100, 120_000, 1e-3, "measured"), None);
    }
}
