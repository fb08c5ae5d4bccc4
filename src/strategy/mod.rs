//! How sensor maps are batched: the strategy kinds, their self-check, the cache of results, and the choice
//! of a strategy for a device (docs/DESIGN.md §5). The strategies themselves are GPU passes
//! (`passes::sensor_maps`); this module only decides which one to use. It renders nothing itself: what it
//! must measure, it asks of a [`Prober`] (the renderer), so it depends on no pass and no oracle.
//!
//! A strategy is used on a device only after a self-check: on a fixed probe (the built-in lightbox,
//! [`CHECK_SENSORS`] sensors in batches of [`CHECK_BATCH`], so that full and partial batches and several
//! multiview groups all occur) its R must equal `per-sensor`'s. `auto` then measures the strategies that
//! pass at the requested sensor size and takes the fastest. Both results are cached per device, driver and
//! build, so a later run pays for neither.

mod cache;
mod choose;

use std::fmt;

use clap::ValueEnum;
use glam::Vec4;
use serde::{Deserialize, Serialize};

pub use cache::{Cache, device_key};
pub use choose::{Choice, Event, Prober, choose, self_check};

/// One way of rendering a batch of sensor maps (see `passes::sensor_maps` for each).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum StrategyKind {
    /// One render pass and one submission per sensor (the paper's DX9 loop; the baseline).
    PerSensor,
    /// One render pass per sensor, a batch of them in one command buffer.
    SingleCb,
    /// `VK_KHR_multiview`: view i of a pass draws into layer i.
    Multiview,
    /// One instanced draw per batch, `gl_Layer` from the vertex shader.
    #[default]
    Layered,
    /// One draw per view into its tile of one large 2D image (its viewport); used only when named.
    Atlas,
    /// A compute shader rasterizes the batch, a workgroup per map layer (no graphics pipeline).
    Compute,
}

impl StrategyKind {
    pub const ALL: [StrategyKind; 6] =
        [Self::PerSensor, Self::SingleCb, Self::Multiview, Self::Layered, Self::Atlas, Self::Compute];

    pub fn name(self) -> &'static str {
        match self {
            Self::PerSensor => "per-sensor",
            Self::SingleCb => "single-cb",
            Self::Multiview => "multiview",
            Self::Layered => "layered",
            Self::Atlas => "atlas",
            Self::Compute => "compute",
        }
    }

    /// Whether it draws every view at the origin of a target of its own, as per-sensor does, so that its
    /// maps, and R, can be per-sensor's bit for bit. The atlas draws at its tiles' offsets, whose window
    /// coordinates round differently in their last bits: a silhouette texel moves now and then (relative
    /// RMSE of R ~1e-4 on the shipped scenes), which a probe of a few sensors need not see; `compute`
    /// computes coverage in floating point, not the hardware's snapped fixed point.
    pub fn rasterizes_like_per_sensor(self) -> bool {
        !matches!(self, Self::Atlas | Self::Compute)
    }
}

impl fmt::Display for StrategyKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The strategy asked for: `auto` (the fastest that passes its self-check here) or a named one (used only
/// if it passes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StrategyRequest {
    #[default]
    Auto,
    Fixed(StrategyKind),
}

impl ValueEnum for StrategyRequest {
    fn value_variants<'a>() -> &'a [Self] {
        &[
            Self::Auto,
            Self::Fixed(StrategyKind::PerSensor),
            Self::Fixed(StrategyKind::SingleCb),
            Self::Fixed(StrategyKind::Multiview),
            Self::Fixed(StrategyKind::Layered),
            Self::Fixed(StrategyKind::Atlas),
            Self::Fixed(StrategyKind::Compute),
        ]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        match self {
            Self::Auto => Some(clap::builder::PossibleValue::new("auto")),
            Self::Fixed(kind) => kind.to_possible_value(),
        }
    }
}

impl fmt::Display for StrategyRequest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Auto => f.write_str("auto"),
            Self::Fixed(kind) => kind.fmt(f),
        }
    }
}

/// Largest difference from `per-sensor`, relative to the probe's brightest R, that still passes. Every
/// strategy rasterises the same views; the atlas draws them at its tiles' offsets, whose window
/// coordinates round differently in their last bits, which may move a silhouette texel (one texel of a 32²
/// map weighs ≲ 1e-3 of a sensor). Such a strategy is used when asked for by name; `auto` takes only
/// strategies whose R is per-sensor's bit for bit ([`CheckResult::identical`]), so that its choice, which
/// depends on timings, never changes the image.
pub const CHECK_TOLERANCE: f32 = 2e-3;
/// Sensor map size of the self-check.
pub const CHECK_RD: u32 = 32;
/// Probe sensors of the self-check, and sensors per batch there (13 = 2 full batches of 5 and a partial one).
pub const CHECK_SENSORS: usize = 13;
pub const CHECK_BATCH: u32 = 5;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckResult {
    /// Largest difference from `per-sensor`, relative to the brightest R of the probe.
    pub max_difference: f32,
    pub passed: bool,
    /// R equals per-sensor's bit for bit at every probe sensor.
    #[serde(default)]
    pub identical: bool,
}

impl CheckResult {
    /// Judges `r` against per-sensor's `reference` R at the same probe sensors.
    pub fn judge(r: &[Vec4], reference: &[Vec4]) -> Self {
        let max_difference = relative_difference(r, reference);
        let bits = |v: &[Vec4]| v.iter().flat_map(|r| r.truncate().to_array().map(f32::to_bits)).collect::<Vec<_>>();
        Self { max_difference, passed: max_difference <= CHECK_TOLERANCE, identical: bits(r) == bits(reference) }
    }
}

/// The largest difference between two sets of R, relative to the brightest of `reference`.
pub fn relative_difference(r: &[Vec4], reference: &[Vec4]) -> f32 {
    let peak = reference.iter().map(|v| v.truncate().max_element()).fold(f32::MIN_POSITIVE, f32::max);
    r.iter().zip(reference).map(|(a, b)| (a.truncate() - b.truncate()).abs().max_element()).fold(0.0, f32::max) / peak
}

/// Sensors the `auto` measurement renders: enough to amortise a submission, few enough to take a moment.
pub fn measure_sensors(rd: u32) -> usize {
    (16_384 * 64 / (rd as usize * rd as usize)).clamp(16, 256)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn request_names_round_trip_through_clap() {
        for request in StrategyRequest::value_variants() {
            let name = request.to_string();
            assert_eq!(StrategyRequest::from_str(&name, false).unwrap(), *request);
        }
        assert!(StrategyRequest::from_str("warp", false).is_err());
    }

    #[test]
    fn a_difference_above_the_tolerance_fails() {
        let reference = [Vec4::new(1.0, 0.5, 0.25, 1.0), Vec4::new(2.0, 2.0, 2.0, 1.0)];
        let mut r = reference;
        assert!(CheckResult::judge(&r, &reference).identical);
        r[1].y = f32::from_bits(r[1].y.to_bits() + 1);
        let last_bit = CheckResult::judge(&r, &reference);
        assert!(last_bit.passed && !last_bit.identical, "one ulp passes but is not identical");
        r[0].x += 2.0 * CHECK_TOLERANCE * 2.0;
        let result = CheckResult::judge(&r, &reference);
        assert!(!result.passed && (result.max_difference - 2.0 * CHECK_TOLERANCE).abs() < 1e-6);
    }
}
