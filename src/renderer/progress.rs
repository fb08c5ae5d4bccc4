//! What a render tells its caller while it runs: its phases, rounds, the radiance cache's levels and bounces,
//! previews, and whether to stop.

use glam::Vec4;

use super::{BounceDone, CacheLevel};
use crate::cancel::Reason;
use crate::scene::ImageSize;

/// The steps of a render (docs/DESIGN.md §3), for progress displays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The G-buffer pass and its read-back.
    GBuffer,
    /// The radiance cache's bounces (global illumination).
    Bounces,
    /// Rounds of sensing and refinement.
    Sensing,
    /// Interpolation, filter, composition and the read-back of the image.
    Post,
}

/// A refinement round, judged: how much of the image is final. The total work of a render is not known up
/// front (each round decides the next), but pixels resolved (by sensing or interpolation) only grow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RoundDone {
    /// 1-based.
    pub round: u32,
    /// Sensors the round rendered.
    pub sensors: u64,
    /// Pixels whose value is decided, of `pixels`.
    pub resolved_pixels: u64,
    pub pixels: u64,
}

/// The render so far, after a round's sensors are done: for previews.
pub struct Snapshot {
    /// 1-based.
    pub round: u32,
    pub size: ImageSize,
    /// `Le + albedo·R` with R interpolated over every quad, judged or not, and not filtered.
    pub image: Vec<Vec4>,
}

/// Progress callbacks for long renders. Every method does nothing by default.
pub trait Progress {
    /// A step of the render begins.
    fn phase(&self, _phase: Phase) {}
    /// `n` more sensors will be rendered (once per round).
    fn queued(&self, _n: u64) {}
    /// `n` more sensors are done.
    fn done(&self, _n: u64) {}
    /// A round's results were judged.
    fn round(&self, _round: &RoundDone) {}
    /// The radiance cache's walk (`gi::reach`) begins a level: its sensors are [`Progress::queued`] next.
    fn cache_level(&self, _level: &CacheLevel) {}
    /// A bounce of the radiance cache is done (its sensors, if any, were [`Progress::queued`] and
    /// [`Progress::done`] in [`Phase::Bounces`]).
    fn bounce(&self, _bounce: &BounceDone) {}
    /// Whether [`Progress::snapshot`] should see round `round` (1-based): building one costs a pass over the
    /// image on the host.
    fn wants_snapshot(&self, _round: u32) -> bool {
        false
    }
    /// The image after a round, when [`Progress::wants_snapshot`] said so.
    fn snapshot(&self, _snapshot: &Snapshot) {}
    /// Whether to stop: asked before each batch of sensors (the radiance cache's and the camera's). The
    /// render then waits for the batches in flight and returns [`Cancelled`](crate::cancel::Cancelled).
    fn cancelled(&self) -> Option<Reason> {
        None
    }
}

/// No progress reporting.
pub struct Quiet;
impl Progress for Quiet {}
