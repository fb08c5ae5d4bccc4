//! [`Detail::Auto`] measured: for a mesh of at least [`DETAIL_PROBE_MIN_TRIANGLES`] triangles, whether the
//! sensor maps draw it at full detail or from its clusters (docs/DESIGN.md §9) is
//! decided by sensing some of the scene's own pixels both ways on the device, once per device, mesh,
//! sensor setting and strategy (remembered in the strategy cache; the strategies' costs per triangle differ). Which way is cheaper depends on the device: on
//! lavapipe the clusters cost as much as full detail at a few dozen triangles and 6× less at 2 000, a GPU
//! draws small meshes cheaper.
//!
//! The clusters are kept only where they are at least [`CLUSTER_GAIN`] times faster and their R is within
//! the strategy self-check's tolerance of full detail's at every probe sensor: the choice depends on
//! timings, so it must not be a coin toss between two images (and once made, it is remembered).
//!
//! Full detail costs in proportion to the triangles (a second a sensor at a million on lavapipe), so the
//! clusters are sensed first and full detail on [`QUICK_SENSORS`] of the same pixels: where that already
//! takes [`CLEARLY_SLOWER`] times the clusters' time, the clusters are kept on those sensors' R, without
//! sensing the rest at full detail.

use std::sync::Arc;
use std::time::Duration;

use anyhow::Result;
use glam::{Vec3, Vec4};

use super::{Detail, Renderer, RendererConfig};
use crate::params::{FrameParams, Indirect};
use crate::scene::{ImageSize, NO_SURFACE, Scene};
use crate::strategy::{self, Cache, Choice, StrategyKind};
use crate::vk::Device;

/// Below this many triangles full detail is kept without measuring: the clusters cannot draw fewer.
pub const DETAIL_PROBE_MIN_TRIANGLES: usize = 256;

/// How much faster the clusters must sense the probe to be kept.
pub const CLUSTER_GAIN: f64 = 1.25;

/// Probe sensors: surface pixels spread over a G-buffer of the scene's camera at this size.
const PROBE_SIZE: ImageSize = ImageSize { width: 32, height: 24 };
const PROBE_SENSORS: usize = 48;

/// Probe sensors full detail senses first, and how much slower than the clusters that must be to decide
/// without the others.
pub const QUICK_SENSORS: usize = 4;
pub const CLEARLY_SLOWER: f64 = 4.0;

/// What the measurement found, for the user.
#[derive(Clone, Debug, PartialEq)]
pub struct DetailProbe {
    pub detail: Detail,
    /// Host time per probe sensor at full detail and from the clusters (none: remembered from before).
    pub times: Option<(Duration, Duration)>,
    /// R's largest difference between the two, relative to the brightest.
    pub difference: Option<f32>,
}

/// `config.detail` made concrete for `scene` on `device` with `strategy` (module docs); `None` where it
/// was not measured.
pub(super) fn measure(
    device: &Arc<Device>,
    scene: &Scene,
    config: &RendererConfig,
    strategy: StrategyKind,
    cache: &mut Cache,
) -> Result<Option<DetailProbe>> {
    let triangles = scene.mesh.triangles.len();
    if config.detail != Detail::Auto
        || triangles < DETAIL_PROBE_MIN_TRIANGLES
        || crate::passes::sensor_maps::culling_unsupported(device, 0).is_some()
    {
        return Ok(None);
    }
    let key = format!(
        "{} | detail | {:016x} | {} {} | {} | {strategy}",
        strategy::device_key(&device.adapter),
        crate::clusters::cache::mesh_key(&scene.mesh),
        config.sensor,
        config.sensor_size,
        config.estimator
    );
    if let Some(clusters) = cache.cluster_choice(&key) {
        let detail = if clusters { Detail::Clusters } else { Detail::Full };
        return Ok(Some(DetailProbe { detail, times: None, difference: None }));
    }
    let frame = FrameParams::every_pixel(Indirect::Epsilon(0.0), Vec3::ZERO);
    // The probe's renderer drawing `detail`, and its pixels (`None`: the device cannot draw the clusters,
    // or the camera sees nothing).
    let renderer = |detail: Detail| -> Result<Option<(Renderer, Vec<u32>)>> {
        let config = RendererConfig { detail, cache: None, ..*config };
        let choice = Choice { strategy, reason: "the detail probe".into() };
        let renderer = Renderer::new(device, scene, config, choice)?;
        if detail == Detail::Clusters && !renderer.culled() {
            return Ok(None);
        }
        let (_, g) = renderer.render_gbuffer(PROBE_SIZE)?;
        let seen: Vec<u32> = (0..g.surface.len() as u32).filter(|&i| g.surface[i as usize] != NO_SURFACE).collect();
        let step = seen.len().div_ceil(PROBE_SENSORS).max(1);
        let pixels: Vec<u32> = seen.into_iter().step_by(step).collect();
        Ok((!pixels.is_empty()).then_some((renderer, pixels)))
    };
    // R at `pixels` and the time per sensor, after a warm-up on the first (pipelines compiled, caches
    // filled; one sensor, which at full detail of a large mesh takes a while).
    let sense = |renderer: &mut Renderer, pixels: &[u32]| -> Result<(Vec<Vec4>, Duration)> {
        renderer.sense_at(PROBE_SIZE, &pixels[..1], &frame)?;
        let (r, time) = renderer.sense_at(PROBE_SIZE, pixels, &frame)?;
        Ok((r, time / pixels.len() as u32))
    };
    let Some((mut culled, pixels)) = renderer(Detail::Clusters)? else {
        return Ok(None);
    };
    let (clusters, cluster_time) = sense(&mut culled, &pixels)?;
    drop(culled);
    let Some((mut whole, _)) = renderer(Detail::Full)? else {
        return Ok(None);
    };
    let quick = &pixels[..pixels.len().min(QUICK_SENSORS)];
    let (mut full, mut full_time) = sense(&mut whole, quick)?;
    let clearly_slower = full_time.as_secs_f64() >= CLEARLY_SLOWER * CLUSTER_GAIN * cluster_time.as_secs_f64();
    if !clearly_slower && quick.len() < pixels.len() {
        (full, full_time) = sense(&mut whole, &pixels)?;
    }
    let difference = strategy::relative_difference(&clusters[..full.len()], &full);
    let faster = full_time.as_secs_f64() >= CLUSTER_GAIN * cluster_time.as_secs_f64();
    let use_clusters = faster && difference <= strategy::CHECK_TOLERANCE;
    cache.record_cluster_choice(key, use_clusters);
    cache.save()?;
    let detail = if use_clusters { Detail::Clusters } else { Detail::Full };
    Ok(Some(DetailProbe { detail, times: Some((full_time, cluster_time)), difference: Some(difference) }))
}
