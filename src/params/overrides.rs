//! Values set on the command line or in a scene file's `[render]` table, and their checks.

use std::path::Path;

use serde::Deserialize;

use super::*;

/// Values set on the command line or in a scene file's `[render]` table; `None` falls back (flag → scene
/// → default). The field names are the `[render]` keys.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Overrides {
    pub estimator: Option<EstimatorKind>,
    pub sensor: Option<SensorShape>,
    pub fov_deg: Option<f32>,
    pub epsilon: Option<f32>,
    pub bounces: Option<Bounces>,
    /// Radiance of rays that leave the scene, linear RGB.
    pub background: Option<[f32; 3]>,
    pub sensor_size: Option<u32>,
    pub tile: Option<u32>,
    pub dradiance: Option<f32>,
    pub filter_radius: Option<u32>,
    pub indirect_filter_radius: Option<u32>,
    pub cache_resolution: Option<u32>,
    pub cache_sensor_size: Option<u32>,
    pub exposure: Option<f32>,
    pub aa: Option<Antialiasing>,
}

impl Overrides {
    /// The `[render]` table of the scene file `path` (empty when the file has none).
    pub fn from_scene_table(path: &Path, table: &toml::Table) -> anyhow::Result<Self> {
        Self::deserialize(toml::Value::Table(table.clone()))
            .map_err(|e| anyhow::anyhow!("{}: [render]: {}", path.display(), e.message()))
    }

    /// Checks every value that is set against its range (ranges that depend on the device are checked when
    /// the renderer is built); errors carry `origin`.
    pub(super) fn check(&self, origin: &Origin) -> Result<(), ParamError> {
        let fail = |param, problem: String| Err(ParamError { param, problem, origin: Some(origin.clone()) });
        if let Some(fov) = self.fov_deg
            && !(fov.is_finite() && fov > 0.0 && fov < 180.0)
        {
            return fail(
                Param::Fov,
                format!("must lie strictly between 0 and 180 degrees (a perspective view cannot see 180°), got {fov}"),
            );
        }
        if let Some(e) = self.epsilon
            && !(e.is_finite() && e >= 0.0)
        {
            return fail(Param::Epsilon, format!("must be a finite number ≥ 0, got {e}"));
        }
        if let (Some(e), Some(b)) = (self.epsilon, self.bounces) {
            return fail(
                Param::Bounces,
                format!(
                    "{b} cannot be combined with {} {e}: ε is the paper's constant in place of reflected light, \
                     bounces compute that light; give one",
                    Param::Epsilon.as_set(origin)
                ),
            );
        }
        if let Some(b) = self.background
            && !b.iter().all(|v| v.is_finite() && *v >= 0.0)
        {
            return fail(Param::Background, format!("must be finite and ≥ 0, got {b:?}"));
        }
        if let Some(rd) = self.sensor_size
            && rd < 2
        {
            return fail(Param::SensorSize, format!("must be at least 2 texels, got {rd}"));
        }
        if let Some(tile) = self.tile
            && !tile.is_power_of_two()
        {
            return fail(Param::Tile, format!("must be a power of two (1, 2, 4, …), got {tile}"));
        }
        if let Some(d) = self.dradiance
            && !(d.is_finite() && d >= 0.0)
        {
            return fail(Param::Dradiance, format!("must be a finite number ≥ 0, got {d}"));
        }
        for (param, radius) in
            [(Param::FilterRadius, self.filter_radius), (Param::IndirectFilterRadius, self.indirect_filter_radius)]
        {
            if let Some(r) = radius
                && r > MAX_FILTER_RADIUS
            {
                return fail(
                    param,
                    format!(
                        "must be at most {MAX_FILTER_RADIUS} pixels (σ = radius / 2; the cost grows with radius²), got {r}"
                    ),
                );
            }
        }
        if let Some(n) = self.cache_resolution
            && !(1..=MAX_CACHE_RESOLUTION).contains(&n)
        {
            return fail(Param::CacheResolution, format!("must be 1 to {MAX_CACHE_RESOLUTION} cells, got {n}"));
        }
        if let Some(x) = self.exposure
            && !x.is_finite()
        {
            return fail(Param::Exposure, format!("must be finite, got {x}"));
        }
        Ok(())
    }
}
