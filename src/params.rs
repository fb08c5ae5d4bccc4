//! The algorithm's parameters: one place for their defaults, ranges and checks. Precedence: command-line
//! flag, then the scene file's `[render]` table, then the defaults below.

use anyhow::{Result, ensure};
use glam::Vec3;

use crate::scene::RenderDefaults;
use crate::sensors::SensorKind;

/// What a sensor sees (DESIGN.md §1–2); shared by the GPU renderer and the CPU reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatorParams {
    /// `hemicube` (default; the whole hemisphere) or `frustum` (the paper's single view of `fov`).
    pub sensor: SensorKind,
    /// ε: a non-emitting surface seen by a sensor returns `Kd·ε` (paper eq. 2), standing in for the light it
    /// reflects. Radiance units; ≥ 0; 0 gives direct lighting only. Typical 0.05–0.3 for scenes whose lights
    /// have `Ke` ≈ 10–20.
    pub epsilon: f32,
    /// Radiance of rays that leave the scene (linear RGB, ≥ 0). Default black.
    pub background: Vec3,
}

/// The full set for `render`: the estimator plus the sensor map size, refinement and filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderParams {
    pub estimator: EstimatorParams,
    /// rd: sensor map side in texels, 2 …  the device's largest image side (even for hemicubes). Noise falls
    /// and cost grows roughly with rd²; 64–256 typical (the paper: 256).
    pub sensor_size: u32,
    /// dt: initial grid step of the adaptive refinement (paper §III-G), a power of two ≥ 1; 16 typical.
    pub tile: u32,
    /// Largest relative variation of R between a quad's corners that is still interpolated; ≥ 0.
    /// 0 senses every pixel; 0.1–0.4 typical (0.2: the Cornell box at 256² within 0.3 % of the error of
    /// 0.1 against the CPU reference, in 60 % of the time); a huge value senses only the grid.
    pub dradiance: f32,
    /// Radius in pixels of the id-constrained Gaussian filter (paper §III-H), σ = radius / 2; 0 = off.
    pub filter_radius: u32,
    /// Exposure of the PNG preview in stops (the EXR is never scaled).
    pub exposure: f32,
}

pub const DEFAULT_SENSOR: &str = "hemicube";
pub const DEFAULT_EPSILON: f32 = 0.1;
pub const DEFAULT_SENSOR_SIZE: u32 = 256;
pub const DEFAULT_TILE: u32 = 16;
pub const DEFAULT_DRADIANCE: f32 = 0.2;
pub const DEFAULT_FILTER_RADIUS: u32 = 2;

/// Values given on the command line; `None` falls back to the scene file, then to the default.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    pub sensor: Option<String>,
    pub fov_deg: Option<f32>,
    pub epsilon: Option<f32>,
    pub background: Option<[f32; 3]>,
    pub sensor_size: Option<u32>,
    pub tile: Option<u32>,
    pub dradiance: Option<f32>,
    pub filter_radius: Option<u32>,
    pub exposure: Option<f32>,
}

impl EstimatorParams {
    pub fn resolve(scene: &RenderDefaults, cli: &Overrides) -> Result<Self> {
        let name = cli.sensor.clone().or_else(|| scene.sensor.clone()).unwrap_or_else(|| DEFAULT_SENSOR.into());
        let fov = cli.fov_deg.or(scene.fov_deg).unwrap_or(SensorKind::DEFAULT_FOV_DEG);
        let epsilon = cli.epsilon.or(scene.epsilon).unwrap_or(DEFAULT_EPSILON);
        let background = Vec3::from(cli.background.or(scene.background).unwrap_or([0.0; 3]));
        ensure!(epsilon.is_finite() && epsilon >= 0.0, "--epsilon must be a finite number ≥ 0, got {epsilon}");
        ensure!(
            background.is_finite() && background.min_element() >= 0.0,
            "--background must be finite and ≥ 0, got {background}"
        );
        Ok(Self { sensor: SensorKind::parse(&name, fov)?, epsilon, background })
    }
}

impl RenderParams {
    /// Resolves and checks everything that does not depend on the device (the sensor size's upper bound does:
    /// see [`SensorKind::check_size`]).
    pub fn resolve(scene: &RenderDefaults, cli: &Overrides) -> Result<Self> {
        let estimator = EstimatorParams::resolve(scene, cli)?;
        let sensor_size = cli.sensor_size.or(scene.sensor_size).unwrap_or(DEFAULT_SENSOR_SIZE);
        let tile = cli.tile.or(scene.tile).unwrap_or(DEFAULT_TILE);
        let dradiance = cli.dradiance.or(scene.dradiance).unwrap_or(DEFAULT_DRADIANCE);
        let filter_radius = cli.filter_radius.or(scene.filter_radius).unwrap_or(DEFAULT_FILTER_RADIUS);
        let exposure = cli.exposure.or(scene.exposure).unwrap_or(0.0);
        ensure!(sensor_size >= 2, "--sensor-size must be at least 2 texels, got {sensor_size}");
        ensure!(tile.is_power_of_two(), "--tile must be a power of two (1, 2, 4, …), got {tile}");
        ensure!(dradiance.is_finite() && dradiance >= 0.0, "--dradiance must be a finite number ≥ 0, got {dradiance}");
        ensure!(exposure.is_finite(), "--exposure must be finite");
        Ok(Self { estimator, sensor_size, tile, dradiance, filter_radius, exposure })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn precedence_is_cli_then_scene_then_default() {
        let scene = RenderDefaults { epsilon: Some(0.5), tile: Some(8), ..Default::default() };
        let cli = Overrides { epsilon: Some(0.25), ..Default::default() };
        let p = RenderParams::resolve(&scene, &cli).unwrap();
        assert_eq!((p.estimator.epsilon, p.tile, p.sensor_size), (0.25, 8, DEFAULT_SENSOR_SIZE));
        assert_eq!(p.estimator.sensor, SensorKind::Hemicube);
    }

    #[test]
    fn bad_values_are_rejected_with_the_flag_named() {
        let bad = [
            Overrides { epsilon: Some(-0.1), ..Default::default() },
            Overrides { tile: Some(12), ..Default::default() },
            Overrides { sensor_size: Some(0), ..Default::default() },
            Overrides { sensor: Some("frustum".into()), fov_deg: Some(180.0), ..Default::default() },
            Overrides { sensor: Some("fisheye".into()), ..Default::default() },
            Overrides { dradiance: Some(f32::NAN), ..Default::default() },
        ];
        for (cli, flag) in
            bad.iter().zip(["--epsilon", "--tile", "--sensor-size", "--fov", "sensor kind", "--dradiance"])
        {
            let e = RenderParams::resolve(&RenderDefaults::default(), cli).unwrap_err().to_string();
            assert!(e.contains(flag), "{e}");
        }
    }
}
