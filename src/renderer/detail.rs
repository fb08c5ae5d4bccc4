//! [`Detail::Auto`] measured: for a mesh of [`DETAIL_PROBE_MIN_TRIANGLES`] to [`CLUSTER_MIN_TRIANGLES`]
//! triangles, whether the sensor maps draw it at full detail or from its clusters (docs/DESIGN.md §9) is
//! decided by sensing some of the scene's own pixels both ways on the device, once per device, mesh,
//! sensor setting and strategy (remembered in the strategy cache; the strategies' costs per triangle differ). Which way is cheaper depends on the device: on
//! lavapipe the clusters cost as much as full detail at a few dozen triangles and 6× less at 2 000, a GPU
//! draws small meshes cheaper.
//!
//! The clusters are kept only where they are at least [`CLUSTER_GAIN`] times faster and their R is within
//! the strategy self-check's tolerance of full detail's at every probe sensor: the choice depends on
//! timings, so it must not be a coin toss between two images (and once made, it is remembered).

use std::sync::Arc;
use std::time::Duration;

use anyhow::Result;
use glam::{Vec3, Vec4};

use super::{CLUSTER_MIN_TRIANGLES, Detail, Renderer, RendererConfig};
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
        || !(DETAIL_PROBE_MIN_TRIANGLES..CLUSTER_MIN_TRIANGLES).contains(&triangles)
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
    let sense = |detail: Detail| -> Result<Option<(Vec<Vec4>, Duration)>> {
        let config = RendererConfig { detail, cache: None, ..*config };
        let choice = Choice { strategy, reason: "the detail probe".into() };
        let mut renderer = Renderer::new(device, scene, config, choice)?;
        if detail == Detail::Clusters && !renderer.culled() {
            return Ok(None); // the device cannot draw this mesh's clusters
        }
        let (_, g) = renderer.render_gbuffer(PROBE_SIZE)?;
        let seen: Vec<u32> = (0..g.surface.len() as u32).filter(|&i| g.surface[i as usize] != NO_SURFACE).collect();
        let step = seen.len().div_ceil(PROBE_SENSORS).max(1);
        let pixels: Vec<u32> = seen.into_iter().step_by(step).collect();
        if pixels.is_empty() {
            return Ok(None);
        }
        renderer.sense_at(PROBE_SIZE, &pixels, &frame)?; // pipelines warm, caches filled
        let (r, time) = renderer.sense_at(PROBE_SIZE, &pixels, &frame)?;
        Ok(Some((r, time / pixels.len() as u32)))
    };
    let (Some((full, full_time)), Some((clusters, cluster_time))) = (sense(Detail::Full)?, sense(Detail::Clusters)?)
    else {
        return Ok(None);
    };
    let difference = strategy::relative_difference(&clusters, &full);
    let faster = full_time.as_secs_f64() >= CLUSTER_GAIN * cluster_time.as_secs_f64();
    let use_clusters = faster && difference <= strategy::CHECK_TOLERANCE;
    cache.record_cluster_choice(key, use_clusters);
    cache.save()?;
    let detail = if use_clusters { Detail::Clusters } else { Detail::Full };
    Ok(Some(DetailProbe { detail, times: Some((full_time, cluster_time)), difference: Some(difference) }))
}
