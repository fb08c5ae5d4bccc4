//! The batching benchmark behind `sensorlight bench`: every strategy that passes its self-check renders
//! the same sensors at each sensor-map size; runs are repeated and interleaved (strategy after strategy,
//! then again) so that a machine's drift hits all alike, and speed is reported as medians with their spread
//! and as ratios measured in the same run: against `per-sensor`, and against the device's raw fill rate
//! (full-screen triangles into the same formats, `passes::fill`). [`run_meshes`] is its triangle-count
//! axis: time per sensor against mesh size, full detail against clusters.

use std::sync::Arc;

use anyhow::Result;
use serde::Serialize;

use crate::params::{EstimatorKind, EstimatorParams, FrameParams, Indirect};
use crate::passes::fill::FillPass;
use crate::renderer::{self, Detail, Renderer, probe_pixels};
use crate::scene::{ImageSize, Scene};
use crate::strategy::{CheckResult, StrategyKind};
use crate::vk::Device;

pub struct BenchConfig {
    pub scene: Scene,
    /// How R is read from the maps (the exact estimator adds a zoom pair of layers per light group).
    pub estimator_kind: EstimatorKind,
    /// The view the sensors are picked from (surface pixels, spread evenly at random).
    pub size: ImageSize,
    pub estimator: EstimatorParams,
    pub sizes: Vec<u32>,
    pub strategies: Vec<StrategyKind>,
    pub sensors: usize,
    pub repeat: usize,
}

/// One strategy at one sensor size.
#[derive(Clone, Debug, Serialize)]
pub struct Measurement {
    pub strategy: StrategyKind,
    pub rd: u32,
    /// Seconds per run of all the sensors, each repeat.
    pub seconds: Vec<f64>,
    pub median_seconds: f64,
    pub sensors_per_second: f64,
    /// Sensor-map texels (all layers) per second, reduction and host work included.
    pub texels_per_second: f64,
    /// Median speed relative to `per-sensor` at this size (when measured).
    pub vs_per_sensor: Option<f64>,
    /// Texel rate relative to the raw fill rate at this size.
    pub vs_fill: f64,
}

/// What does not depend on the strategy, at one sensor size.
#[derive(Clone, Debug, Serialize)]
pub struct SizeSummary {
    pub rd: u32,
    /// Raw fill: texels per second (median).
    pub fill_texels_per_second: f64,
    /// The reduction alone, seconds per sensor (median).
    pub reduction_seconds_per_sensor: f64,
    /// The reduction's share of the fastest strategy's time per sensor.
    pub reduction_share_of_best: f64,
    pub best: StrategyKind,
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub device: String,
    pub driver: String,
    pub scene: String,
    pub triangles: usize,
    pub sensor: String,
    pub sensors: usize,
    pub repeat: usize,
    pub checks: Vec<(StrategyKind, CheckResult)>,
    /// Strategies not measured, and why.
    pub skipped: Vec<(StrategyKind, String)>,
    pub measurements: Vec<Measurement>,
    pub sizes: Vec<SizeSummary>,
}

/// What the benchmark is doing, for progress displays.
#[derive(Clone, Debug)]
pub enum BenchEvent {
    /// A strategy's self-check ran.
    Checked { strategy: StrategyKind, result: CheckResult },
    /// A timed round at sensor size `rd` is done.
    Round { rd: u32, round: usize, rounds: usize },
}

fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// Runs the benchmark; `events` hears of each self-check and each timed round.
pub fn run(device: &Arc<Device>, config: &BenchConfig, events: &mut dyn FnMut(BenchEvent)) -> Result<BenchReport> {
    let sensor = config.estimator.sensor;
    let max_side = device.adapter.limits.max_image_dimension_2d;
    for &rd in &config.sizes {
        if let Some(problem) = sensor.size_problem(rd, max_side) {
            return Err(crate::params::ParamError::new(crate::params::Param::SensorSize, problem).into());
        }
    }
    let mut checks = Vec::new();
    let mut skipped = Vec::new();
    let mut strategies = Vec::new();
    for &kind in &config.strategies {
        let rd = config.sizes.iter().copied().max().unwrap_or(32);
        if let Some(why) = renderer::unsupported(device, &config.scene, (sensor, config.estimator_kind, rd), kind) {
            skipped.push((kind, format!("unsupported: {why}")));
            continue;
        }
        let check = renderer::self_check(device, sensor, config.estimator_kind, kind)?;
        events(BenchEvent::Checked { strategy: kind, result: check });
        checks.push((kind, check));
        if check.passed {
            strategies.push(kind);
        } else {
            skipped.push((
                kind,
                format!("fails the self-check (max difference {:.2e} of the brightest R)", check.max_difference),
            ));
        }
    }

    let frame = FrameParams::every_pixel(
        Indirect::Epsilon(config.estimator.indirect.paper_epsilon()),
        config.estimator.background,
    );
    let layers = sensor.layers() as u64; // the main layers: the fill rate's yardstick
    let mut pixels = Vec::new();
    let mut measurements = Vec::new();
    let mut sizes = Vec::new();
    for &rd in &config.sizes {
        let mut renderers = strategies
            .iter()
            .map(|&kind| {
                Renderer::builder(device, &config.scene, sensor, rd)
                    .estimator(config.estimator_kind)
                    .build_unchecked(kind)
            })
            .collect::<Result<Vec<_>>>()?;
        if pixels.is_empty()
            && let Some(r) = renderers.first()
        {
            pixels = probe_pixels(&r.gbuffer(config.size)?.surface, config.sensors);
        }
        let n = pixels.len();
        let fill_layers = (n as u64 * layers).min(device.adapter.limits.max_framebuffer_layers as u64) as u32;
        let fill = FillPass::new(device, rd, fill_layers)?;
        // Warm-up: pipelines compile at first use.
        for r in &mut renderers {
            r.sense_at(config.size, &pixels, &frame)?;
        }
        fill.run(device)?;
        let mut times = vec![Vec::new(); renderers.len()];
        let (mut fill_rates, mut reductions) = (Vec::new(), Vec::new());
        for round in 0..config.repeat {
            for (i, r) in renderers.iter_mut().enumerate() {
                let (_, t) = r.sense_at(config.size, &pixels, &frame)?;
                times[i].push(t.as_secs_f64());
            }
            let t = fill.run(device)?;
            fill_rates.push(fill_layers as f64 * (rd as f64).powi(2) / t.as_secs_f64());
            if let Some(r) = renderers.iter_mut().find(|r| r.strategy() != StrategyKind::Atlas) {
                let count = (n as u32).min(r.batch_size());
                reductions.push(r.time_reduction(count)?.as_secs_f64() / count as f64);
            }
            events(BenchEvent::Round { rd, round: round + 1, rounds: config.repeat });
        }
        let fill_rate = median(&fill_rates);
        let texels_per_sensor = layers as f64 * (rd as f64).powi(2);
        let per_sensor_median =
            strategies.iter().position(|k| *k == StrategyKind::PerSensor).map(|i| median(&times[i]));
        let first = measurements.len();
        for (i, &kind) in strategies.iter().enumerate() {
            let m = median(&times[i]);
            let sensors_per_second = n as f64 / m;
            measurements.push(Measurement {
                strategy: kind,
                rd,
                seconds: times[i].clone(),
                median_seconds: m,
                sensors_per_second,
                texels_per_second: sensors_per_second * texels_per_sensor,
                vs_per_sensor: per_sensor_median.map(|p| p / m),
                vs_fill: sensors_per_second * texels_per_sensor / fill_rate,
            });
        }
        let best = measurements[first..].iter().min_by(|a, b| a.median_seconds.total_cmp(&b.median_seconds));
        let reduction = if reductions.is_empty() { 0.0 } else { median(&reductions) };
        if let Some(best) = best {
            sizes.push(SizeSummary {
                rd,
                fill_texels_per_second: fill_rate,
                reduction_seconds_per_sensor: reduction,
                reduction_share_of_best: reduction / (best.median_seconds / n as f64),
                best: best.strategy,
            });
        }
        drop(renderers);
    }
    Ok(BenchReport {
        device: device.adapter.name.clone(),
        driver: device.adapter.driver.clone(),
        scene: config.scene.path.display().to_string(),
        triangles: config.scene.mesh.triangles.len(),
        sensor: sensor.to_string(),
        sensors: pixels.len(),
        repeat: config.repeat,
        checks,
        skipped,
        measurements,
        sizes,
    })
}

impl BenchReport {
    /// The measurements as CSV, one row per strategy and size.
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "device,driver,sensor,rd,strategy,sensors,repeat,median_seconds,min_seconds,max_seconds,sensors_per_second,texels_per_second,vs_per_sensor,vs_fill\n",
        );
        for m in &self.measurements {
            let min = m.seconds.iter().copied().fold(f64::INFINITY, f64::min);
            let max = m.seconds.iter().copied().fold(0.0, f64::max);
            out.push_str(&format!(
                "\"{}\",\"{}\",{},{},{},{},{},{:.6},{:.6},{:.6},{:.1},{:.4e},{},{:.4}\n",
                self.device,
                self.driver,
                self.sensor,
                m.rd,
                m.strategy,
                self.sensors,
                self.repeat,
                m.median_seconds,
                min,
                max,
                m.sensors_per_second,
                m.texels_per_second,
                m.vs_per_sensor.map(|v| format!("{v:.3}")).unwrap_or_default(),
                m.vs_fill
            ));
        }
        out
    }
}

/// The triangle-count axis of `sensorlight bench --scenes`: the same strategy on scenes of growing meshes,
/// each at full detail and drawn from its clusters (docs/DESIGN.md §9), time per sensor against the first
/// scene's (the plain one) measured in the same run.
pub struct MeshBenchConfig {
    /// (name, scene), the baseline first.
    pub scenes: Vec<(String, Scene)>,
    pub estimator_kind: EstimatorKind,
    pub size: ImageSize,
    pub estimator: EstimatorParams,
    pub sizes: Vec<u32>,
    pub strategy: StrategyKind,
    pub sensors: usize,
    pub repeat: usize,
    /// Full detail only up to this many triangles (it costs time in proportion to them).
    pub max_full_detail: usize,
    /// Also time the clusters drawn whole ([`Detail::WholeClusters`]: no triangle pass).
    pub whole_clusters: bool,
}

/// One scene at one sensor size and detail.
#[derive(Clone, Debug, Serialize)]
pub struct MeshMeasurement {
    pub scene: String,
    pub triangles: usize,
    pub rd: u32,
    pub detail: Detail,
    pub sensors: usize,
    /// Seconds per run of all the sensors, each repeat.
    pub seconds: Vec<f64>,
    pub ms_per_sensor: f64,
    /// Culled: triangles the maps drew per sensor, all its views.
    pub drawn_triangles_per_sensor: Option<f64>,
    /// The last round's device time per sensor (timestamps, where the device writes them): the culling
    /// and triangle passes, and the maps (the emitter pass included).
    pub gpu_cull_ms_per_sensor: Option<f64>,
    pub gpu_maps_ms_per_sensor: Option<f64>,
    /// Clusters the triangle pass left whole per sensor (their view's region of its pool full), last round.
    pub whole_clusters_per_sensor: f64,
    /// Time per sensor against the first scene's at the same size and detail (full detail: the first
    /// scene's full detail; clusters: its full detail too, the image the others are held to).
    pub vs_first: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct MeshReport {
    pub device: String,
    pub driver: String,
    pub strategy: StrategyKind,
    pub sensor: String,
    pub repeat: usize,
    pub measurements: Vec<MeshMeasurement>,
}

/// Runs the triangle-count benchmark: per size, every (scene, detail) renderer senses its own probe pixels
/// once to warm up, then `repeat` timed rounds, interleaved.
pub fn run_meshes(
    device: &Arc<Device>,
    config: &MeshBenchConfig,
    events: &mut dyn FnMut(BenchEvent),
) -> Result<MeshReport> {
    let sensor = config.estimator.sensor;
    let frame = FrameParams::every_pixel(
        Indirect::Epsilon(config.estimator.indirect.paper_epsilon()),
        config.estimator.background,
    );
    let mut measurements = Vec::new();
    for &rd in &config.sizes {
        let mut runs = Vec::new();
        for (name, scene) in &config.scenes {
            let triangles = scene.mesh.triangles.len();
            for detail in [Detail::Full, Detail::WholeClusters, Detail::Clusters] {
                if (detail == Detail::Full && triangles > config.max_full_detail)
                    || (detail == Detail::WholeClusters && !config.whole_clusters)
                {
                    continue;
                }
                let mut r = Renderer::builder(device, scene, sensor, rd)
                    .estimator(config.estimator_kind)
                    .detail(detail)
                    .build_unchecked(config.strategy)?;
                if detail != Detail::Full && !r.culled() {
                    continue; // the device cannot draw from clusters: nothing to compare
                }
                let pixels = probe_pixels(&r.gbuffer(config.size)?.surface, config.sensors);
                r.sense_at(config.size, &pixels, &frame)?;
                let drawn = r.batch_times().drawn_triangles.map(|t| t as f64 / pixels.len().max(1) as f64);
                runs.push((name.clone(), triangles, detail, r, pixels, drawn, Vec::new()));
            }
        }
        for round in 0..config.repeat {
            for (_, _, _, r, pixels, _, seconds) in &mut runs {
                let (_, t) = r.sense_at(config.size, pixels, &frame)?;
                seconds.push(t.as_secs_f64());
            }
            events(BenchEvent::Round { rd, round: round + 1, rounds: config.repeat });
        }
        let per_sensor = |seconds: &[f64], n: usize| 1e3 * median(seconds) / n.max(1) as f64;
        let baseline = runs.first().map(|(_, _, _, _, p, _, s)| per_sensor(s, p.len())).unwrap_or(f64::NAN);
        for (scene, triangles, detail, r, pixels, drawn, seconds) in runs {
            let ms = per_sensor(&seconds, pixels.len());
            let times = r.batch_times();
            let device_ms =
                |d: Option<std::time::Duration>| d.map(|d| 1e3 * d.as_secs_f64() / pixels.len().max(1) as f64);
            measurements.push(MeshMeasurement {
                scene,
                triangles,
                rd,
                detail,
                sensors: pixels.len(),
                seconds,
                ms_per_sensor: ms,
                drawn_triangles_per_sensor: drawn,
                gpu_cull_ms_per_sensor: device_ms(times.gpu_cull),
                gpu_maps_ms_per_sensor: device_ms(times.gpu_maps),
                whole_clusters_per_sensor: times.whole_clusters as f64 / pixels.len().max(1) as f64,
                vs_first: ms / baseline,
            });
        }
    }
    Ok(MeshReport {
        device: device.adapter.name.clone(),
        driver: device.adapter.driver.clone(),
        strategy: config.strategy,
        sensor: sensor.to_string(),
        repeat: config.repeat,
        measurements,
    })
}
