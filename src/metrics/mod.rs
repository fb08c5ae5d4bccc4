//! The paper's three metrics (§IV), measured on the current device:
//!
//! - **Table I**: sensor time (total render time / sensors) against screen resolution, fixed map size;
//! - **Fig. 10**: sensor time against sensor map size, for three resolutions;
//! - **Fig. 11**: number of sensors against sensor map size, for the same resolutions.
//!
//! Figures 10 and 11 come from the same renders. One [`Renderer`] serves every render of a map size, so
//! pipeline creation is not counted; each render's own time (G-buffer to composition) is. [`compare`]
//! measures an image's error against a reference's (`sensorlight compare`, docs/ACCURACY.md).

pub mod compare;
mod picture;
pub mod report;

use std::sync::Arc;

use anyhow::Result;
use serde::Serialize;

use crate::params::{FrameParams, Indirect, RenderParams};
use crate::renderer::{Progress, RenderStats, Renderer};
use crate::scene::{ImageSize, Scene};
use crate::strategy::{Cache, StrategyRequest};
use crate::vk::Device;

/// The paper's Table I (GTX 660, DirectX 9, 256² maps): (width, height, sensors, ms per sensor).
pub const PAPER_TABLE1: [(u32, u32, u64, f64); 13] = [
    (200, 200, 15_240, 4.455),
    (300, 200, 23_762, 4.439),
    (400, 300, 40_271, 4.499),
    (500, 300, 44_300, 4.496),
    (500, 400, 55_904, 4.541),
    (600, 400, 63_074, 4.581),
    (600, 500, 68_276, 4.531),
    (700, 500, 79_158, 4.587),
    (700, 600, 83_423, 4.588),
    (800, 600, 96_266, 4.588),
    (900, 600, 108_239, 4.578),
    (900, 700, 112_436, 4.581),
    (1024, 768, 133_822, 4.569),
];

/// The paper's figures 10 and 11 use three resolutions it does not name; these span Table I's range.
pub const FIGURE_RESOLUTIONS: [(u32, u32); 3] = [(320, 240), (640, 480), (1024, 768)];
pub const FIGURE_SIZES: [u32; 5] = [16, 32, 64, 128, 256];

#[derive(Clone, Debug, Serialize)]
pub struct MetricsConfig {
    pub scene: String,
    /// Everything but the map size: Table I uses `params.values.sensor_size`, the figures `figure_sizes`.
    #[serde(skip)]
    pub params: RenderParams,
    pub sensor: String,
    pub table1_sensor_size: u32,
    pub tile: u32,
    pub dradiance: f32,
    pub epsilon: f32,
    pub filter_radius: u32,
    pub table1_resolutions: Vec<ImageSize>,
    pub figure_resolutions: Vec<ImageSize>,
    pub figure_sizes: Vec<u32>,
    #[serde(serialize_with = "crate::metrics::serialize_display")]
    pub strategy: StrategyRequest,
    pub table1: bool,
    pub figures: bool,
}

impl MetricsConfig {
    pub fn new(scene: String, params: RenderParams) -> Self {
        let size = |&(width, height): &(u32, u32)| ImageSize { width, height };
        Self {
            scene,
            sensor: params.estimator.sensor.to_string(),
            table1_sensor_size: params.values.sensor_size,
            tile: params.values.tile,
            dradiance: params.values.dradiance,
            epsilon: params.estimator.indirect.paper_epsilon(),
            filter_radius: params.values.filter_radius,
            params,
            table1_resolutions: PAPER_TABLE1.iter().map(|&(w, h, _, _)| size(&(w, h))).collect(),
            figure_resolutions: FIGURE_RESOLUTIONS.iter().map(size).collect(),
            figure_sizes: FIGURE_SIZES.to_vec(),
            strategy: StrategyRequest::Auto,
            table1: true,
            figures: true,
        }
    }

    /// A reduced run (a couple of minutes on a CPU driver): small maps, Table I at the paper's three smallest
    /// resolutions (so that its values stand beside ours), the figures at smaller ones.
    pub fn quick(mut self) -> Self {
        let size = |width, height| ImageSize { width, height };
        self.table1_resolutions = PAPER_TABLE1[..3].iter().map(|&(w, h, _, _)| size(w, h)).collect();
        self.table1_sensor_size = 32;
        self.figure_resolutions = vec![size(80, 60), size(120, 90), size(160, 120)];
        self.figure_sizes = vec![16, 32, 64];
        self
    }

    /// Renders in order: Table I's, then the figures' (grouped by map size).
    pub fn runs(&self) -> Vec<(Experiment, u32, ImageSize)> {
        let mut runs = Vec::new();
        if self.table1 {
            runs.extend(self.table1_resolutions.iter().map(|&r| (Experiment::Table1, self.table1_sensor_size, r)));
        }
        if self.figures {
            for &rd in &self.figure_sizes {
                runs.extend(self.figure_resolutions.iter().map(|&r| (Experiment::Figures, rd, r)));
            }
        }
        runs
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Experiment {
    Table1,
    /// Figures 10 and 11.
    Figures,
}

/// One render of the metrics.
#[derive(Clone, Debug, Serialize)]
pub struct Run {
    pub experiment: Experiment,
    pub stats: RenderStats,
}

impl Run {
    pub fn resolution(&self) -> String {
        format!("{}x{}", self.stats.width, self.stats.height)
    }
}

/// Renders every run of `config` on `scene`; `each` sees every run as it completes.
pub fn run(
    device: &Arc<Device>,
    scene: &Scene,
    config: &MetricsConfig,
    cache: &mut Cache,
    progress: &dyn Progress,
    each: &mut dyn FnMut(&Run),
) -> Result<Vec<Run>> {
    let sensor = config.params.estimator.sensor;
    // The paper's experiment: its ε, whatever model the scene file asks `render` for.
    // The paper's images: one sample at each pixel's centre.
    let frame = FrameParams {
        indirect: Indirect::Epsilon(config.epsilon),
        aa: crate::params::Antialiasing::Off,
        ..config.params.frame()
    };
    let mut results = Vec::new();
    let mut current: Option<(u32, Renderer)> = None;
    for (experiment, rd, size) in config.runs() {
        let renderer = match current.take() {
            Some((r, renderer)) if r == rd => &mut current.insert((r, renderer)).1,
            previous => {
                drop(previous); // free the previous map size's images first
                let renderer = Renderer::builder(device, scene, sensor, rd)
                    .estimator(config.params.values.estimator)
                    .strategy(config.strategy)
                    .cache(cache)
                    .build()?;
                &mut current.insert((rd, renderer)).1
            }
        };
        let output = renderer.render(size, &frame, progress)?;
        let run = Run { experiment, stats: output.stats };
        each(&run);
        results.push(run);
    }
    Ok(results)
}

/// Serialises a value by its `Display` (e.g. `auto`, `layered`).
pub fn serialize_display<T: std::fmt::Display, S: serde::Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(value)
}

/// Slope of log(y) against log(x) by least squares: the exponent of a power law through the points.
pub fn log_log_slope(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> =
        points.iter().filter(|p| p.0 > 0.0 && p.1 > 0.0).map(|&(x, y)| (x.ln(), y.ln())).collect();
    let n = logs.len() as f64;
    let (mx, my) = (logs.iter().map(|p| p.0).sum::<f64>() / n, logs.iter().map(|p| p.1).sum::<f64>() / n);
    let num: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let den: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    if den > 0.0 { num / den } else { f64::NAN }
}

/// Coefficient of variation (standard deviation / mean) of `values`.
pub fn variation(values: &[f64]) -> f64 {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    var.sqrt() / mean
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_a_power_law_is_its_exponent() {
        let points: Vec<(f64, f64)> = [16.0, 32.0, 64.0, 128.0].iter().map(|&x: &f64| (x, 3.0 * x.powf(1.7))).collect();
        assert!((log_log_slope(&points) - 1.7).abs() < 1e-9);
        assert!(variation(&[2.0, 2.0, 2.0]).abs() < 1e-12);
        assert!((variation(&[1.0, 3.0]) - 0.5).abs() < 1e-12);
    }
}
