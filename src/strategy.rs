//! Choosing how sensor maps are batched (see `passes::sensor_maps`). A strategy is used on a device only
//! after a self-check: on a fixed probe (the built-in lightbox, 13 sensors in batches of 5 so that full
//! and partial batches and several multiview groups all occur) its R must equal `per-sensor`'s. `auto`
//! then measures the strategies that pass at the requested sensor size and takes the fastest. Both results
//! are cached per device, driver and build, so a later run pays for neither.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context as _, Result, bail};
use glam::{Vec3, Vec4};
use serde::{Deserialize, Serialize};

use crate::output::atomic;
use crate::params::EstimatorParams;
use crate::passes::sensor_maps::{self, StrategyDesc, StrategyKind, TEXEL_BYTES};
use crate::reference::{bvh::Bvh, gbuffer, sampling::hash};
use crate::renderer::Renderer;
use crate::scene::{ImageSize, NO_SURFACE, Scene, builtin};
use crate::sensors::SensorKind;
use crate::vk::Device;

/// Largest difference from `per-sensor`, relative to the probe's brightest R, that still passes. The
/// layer strategies rasterise the same views and agree exactly; the atlas remaps clip space, which may move
/// a silhouette texel (one texel of a 32² map weighs ≲ 1e-3 of a sensor).
pub const CHECK_TOLERANCE: f32 = 2e-3;
const CHECK_RD: u32 = 32;
const CHECK_SENSORS: usize = 13;
const CHECK_BATCH: u64 = 5;

/// Fixed sensors on the built-in lightbox.
pub struct Probe {
    pub scene: Scene,
    pub size: ImageSize,
    /// Pixels (with a surface) to place sensors at, spread over the image.
    pub pixels: Vec<u32>,
    pub estimator: EstimatorParams,
}

impl Probe {
    /// `count` sensors on the built-in lightbox seen at 32 × 32, deterministic.
    pub fn new(count: usize) -> Self {
        let size = ImageSize { width: 32, height: 32 };
        let estimator = EstimatorParams { sensor: SensorKind::Hemicube, epsilon: 0.2, background: Vec3::splat(0.05) };
        Self::on(builtin::lightbox(size), size, count, estimator)
    }

    /// `count` sensors (fewer if the image shows fewer surface pixels) on `scene` seen at `size`.
    pub fn on(scene: Scene, size: ImageSize, count: usize, estimator: EstimatorParams) -> Self {
        let g = gbuffer::cast(&scene, &Bvh::build(&scene.mesh.triangles), size);
        let surfaces: Vec<u32> = (0..g.surface.len() as u32).filter(|&i| g.surface[i as usize] != NO_SURFACE).collect();
        let mut pixels: Vec<u32> = Vec::with_capacity(count);
        let mut k = 0u64;
        while pixels.len() < count.min(surfaces.len()) {
            let candidate = surfaces[(hash(k) % surfaces.len() as u64) as usize];
            if !pixels.contains(&candidate) {
                pixels.push(candidate);
            }
            k += 1;
        }
        Self { scene, size, pixels, estimator }
    }

    /// R at the probe's sensors with `strategy`, and the host time sensing took.
    pub fn run(
        &self,
        device: &Arc<Device>,
        sensor: SensorKind,
        rd: u32,
        budget: Option<u64>,
        strategy: StrategyKind,
    ) -> Result<(Vec<Vec4>, Duration)> {
        let mut renderer = Renderer::new(device, &self.scene, sensor, rd, budget, strategy)?;
        let estimator = EstimatorParams { sensor, ..self.estimator };
        renderer.radiance_at(&self.scene, self.size, &self.pixels, &estimator)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckResult {
    /// Largest difference from `per-sensor`, relative to the brightest R of the probe.
    pub max_difference: f32,
    pub passed: bool,
}

/// The largest difference between two sets of R, relative to the brightest of `reference`.
pub fn relative_difference(r: &[Vec4], reference: &[Vec4]) -> f32 {
    let peak = reference.iter().map(|v| v.truncate().max_element()).fold(f32::MIN_POSITIVE, f32::max);
    r.iter().zip(reference).map(|(a, b)| (a.truncate() - b.truncate()).abs().max_element()).fold(0.0, f32::max) / peak
}

/// Checks `strategy` against `per-sensor` for `sensor` sensors on the probe.
pub fn self_check(device: &Arc<Device>, sensor: SensorKind, strategy: StrategyKind) -> Result<CheckResult> {
    let probe = Probe::new(CHECK_SENSORS);
    let budget = Some(CHECK_BATCH * sensor.layers() as u64 * (CHECK_RD as u64).pow(2) * TEXEL_BYTES);
    let (reference, _) = probe.run(device, sensor, CHECK_RD, budget, StrategyKind::PerSensor)?;
    let (r, _) = probe.run(device, sensor, CHECK_RD, budget, strategy)?;
    let max_difference = relative_difference(&r, &reference);
    Ok(CheckResult { max_difference, passed: max_difference <= CHECK_TOLERANCE })
}

/// Self-checks and choices already made, kept in a JSON file.
#[derive(Default, Serialize, Deserialize)]
pub struct Cache {
    #[serde(skip)]
    path: Option<PathBuf>,
    checks: BTreeMap<String, CheckResult>,
    choices: BTreeMap<String, StrategyKind>,
}

impl Cache {
    /// The cache in `$SENSORLIGHT_CACHE_DIR`, else `$XDG_CACHE_HOME/sensorlight`, else `~/.cache/sensorlight`.
    /// A missing or unreadable file is an empty cache.
    pub fn open_default() -> Self {
        let dir = std::env::var_os("SENSORLIGHT_CACHE_DIR").map(PathBuf::from).or_else(|| {
            std::env::var_os("XDG_CACHE_HOME")
                .map(PathBuf::from)
                .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
                .map(|d| d.join("sensorlight"))
        });
        let Some(dir) = dir else { return Self::default() };
        let path = dir.join("strategies.json");
        let mut cache: Self =
            std::fs::read(&path).ok().and_then(|bytes| serde_json::from_slice(&bytes).ok()).unwrap_or_default();
        cache.path = Some(path);
        cache
    }

    /// A cache that is not saved (tests, benchmarks that must measure afresh).
    pub fn in_memory() -> Self {
        Self::default()
    }

    /// Records a self-check result as if it had been run (e.g. to test that `auto` honours a failure).
    pub fn record_check(&mut self, device: &Device, sensor: SensorKind, strategy: StrategyKind, result: CheckResult) {
        self.checks.insert(check_key(&device_key(device), sensor, strategy), result);
    }

    fn save(&self) -> Result<()> {
        let Some(path) = &self.path else { return Ok(()) };
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        atomic::write_bytes(path, &serde_json::to_vec_pretty(self)?)
    }
}

/// Identifies a device, its driver and this build: a new driver or new shaders invalidate what was cached.
fn device_key(device: &Device) -> String {
    // FNV-1a over every shader's SPIR-V.
    let shaders = crate::shaders::ALL
        .iter()
        .flat_map(|(_, spirv)| spirv.iter())
        .fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3));
    format!("{} | {} | {} {:016x}", device.adapter.name, device.adapter.driver, env!("CARGO_PKG_VERSION"), shaders)
}

fn check_key(device_key: &str, sensor: SensorKind, strategy: StrategyKind) -> String {
    format!("{device_key} | {sensor} | {strategy}")
}

/// How a strategy was picked, for the user.
#[derive(Debug)]
pub struct Choice {
    pub strategy: StrategyKind,
    pub reason: String,
}

/// The strategy to use: `requested` if it passes its self-check, else (`None` = auto) the fastest strategy
/// that passes, measured on the probe at `rd`. `log` receives what was checked and measured.
pub fn choose(
    device: &Arc<Device>,
    sensor: SensorKind,
    rd: u32,
    budget: u64,
    requested: Option<StrategyKind>,
    cache: &mut Cache,
    log: &mut dyn FnMut(String),
) -> Result<Choice> {
    let key = device_key(device);
    // Only the sensor kind and size matter to `unsupported`.
    let desc = StrategyDesc { sensor, rd, budget, near: 0.0 };
    let checked = |kind: StrategyKind, cache: &mut Cache, log: &mut dyn FnMut(String)| -> Result<CheckResult> {
        let check_key = check_key(&key, sensor, kind);
        let verdict = |result: &CheckResult| if result.passed { "passes" } else { "FAILS (refused on this device)" };
        if let Some(result) = cache.checks.get(&check_key) {
            // A refusal is worth repeating every time; a pass is not.
            if !result.passed {
                log(format!("self-check (cached): {kind} vs per-sensor: {}", verdict(result)));
            }
            return Ok(*result);
        }
        let result = self_check(device, sensor, kind)?;
        log(format!(
            "self-check: {kind} vs per-sensor: max difference {:.2e} of the brightest R: {}",
            result.max_difference,
            verdict(&result)
        ));
        cache.checks.insert(check_key, result);
        cache.save()?;
        Ok(result)
    };
    if let Some(kind) = requested {
        if let Some(why) = sensor_maps::unsupported(kind, device, &desc) {
            bail!("strategy {kind} cannot run on {}: {why}", device.adapter);
        }
        let result = checked(kind, cache, log)?;
        if !result.passed {
            bail!(
                "strategy {kind} disagrees with per-sensor on {} (max difference {:.2e}); choose another or auto",
                device.adapter,
                result.max_difference
            );
        }
        return Ok(Choice { strategy: kind, reason: "requested".into() });
    }

    let choice_key = format!("{key} | {sensor} | rd {rd} | budget {budget}");
    if let Some(&kind) = cache.choices.get(&choice_key) {
        return Ok(Choice { strategy: kind, reason: "auto: fastest correct strategy here, cached".into() });
    }
    let mut candidates = Vec::new();
    for kind in StrategyKind::ALL {
        if let Some(why) = sensor_maps::unsupported(kind, device, &desc) {
            log(format!("{kind}: unsupported here ({why})"));
        } else if checked(kind, cache, log)?.passed {
            candidates.push(kind);
        }
    }
    let probe = Probe::new(measure_sensors(rd));
    let mut best = Vec::new();
    for kind in &candidates {
        probe.run(device, sensor, rd, Some(budget), *kind)?; // warm-up: pipelines compile lazily
    }
    for _round in 0..2 {
        for (i, kind) in candidates.iter().enumerate() {
            let (_, time) = probe.run(device, sensor, rd, Some(budget), *kind)?;
            let per_sensor = time / probe.pixels.len() as u32;
            if best.len() <= i {
                best.push(per_sensor);
            } else {
                best[i] = best[i].min(per_sensor);
            }
        }
    }
    let Some((index, _)) = best.iter().enumerate().min_by_key(|(_, t)| **t) else {
        bail!("no sensor-map strategy runs correctly on {}", device.adapter);
    };
    let timings: Vec<String> =
        candidates.iter().zip(&best).map(|(k, t)| format!("{k} {:.3} ms", t.as_secs_f64() * 1e3)).collect();
    log(format!("auto: per sensor at rd {rd}: {}", timings.join(", ")));
    let strategy = candidates[index];
    cache.choices.insert(choice_key, strategy);
    cache.save()?;
    Ok(Choice { strategy, reason: "auto: fastest correct strategy here, measured".into() })
}

/// Sensors the `auto` measurement renders: enough to amortise a submission, few enough to take a moment.
fn measure_sensors(rd: u32) -> usize {
    (16_384 * 64 / (rd as usize * rd as usize)).clamp(16, 256)
}
