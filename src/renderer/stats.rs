//! What a render measured, as printed and as written by `--stats-json`: counts, and times split honestly
//! between what the host waited for and what the device did.

use std::time::Duration;

use serde::Serialize;

use super::BatchTimes;
use crate::params::FrameParams;
use crate::scene::ImageSize;
use crate::strategy::StrategyKind;
use crate::vk::Device;

#[derive(Clone, Debug, Serialize)]
pub struct RenderStats {
    pub device: String,
    pub driver: String,
    pub sensor: String,
    pub strategy: StrategyKind,
    pub sensor_size: u32,
    pub width: u32,
    pub height: u32,
    pub tile: u32,
    pub dradiance: f32,
    /// The model of indirect light, as `--bounces` or `--epsilon` name it.
    pub indirect: String,
    pub filter_radius: u32,
    /// The camera's sensors, in total and per refinement round.
    pub sensors: u64,
    pub sensors_per_round: Vec<u64>,
    /// Bytes read back to the host after each round: the R of the sensors it placed.
    pub readback_bytes_per_round: Vec<u64>,
    /// Sensors sensed again at twice the rd where a slit fell between their texels (docs/DESIGN.md §3 step
    /// 5): pixels `sensors` counts once already.
    pub fine_sensors: u64,
    pub interpolated_quads: u64,
    /// Whether pixels are their square (`on`) or their centre.
    pub aa: crate::params::Antialiasing,
    /// Pixels given sub-pixel samples (docs/DESIGN.md §11), and their share of the image.
    pub supersampled_pixels: u64,
    pub supersampled_share: f64,
    /// Global illumination: the radiance cache's bounces (its sensors are not in `sensors`).
    pub gi: Option<super::GiStats>,
    pub batch_size: u32,
    pub batches: u64,
    /// Whether the sensor maps were drawn from the scene's clusters (docs/DESIGN.md §9), and then the
    /// triangles they drew per sensor, all views together, those of the clusters selected (the triangle
    /// pass drops the rest), and the clusters the triangle pass left whole for want of room.
    pub culled: bool,
    pub drawn_triangles_per_sensor: Option<f64>,
    pub selected_triangles_per_sensor: Option<f64>,
    pub whole_clusters: u64,
    pub in_flight: u32,
    /// Wall time of the whole render.
    pub total_seconds: f64,
    /// Wall time building the renderer took before it: the strategy's self-checks and `auto`'s measurement
    /// (near nothing when cached), pipelines. Not in `total_seconds`, which is the render's own (the paper's
    /// sensor time); a renderer serving several renders reports it with each.
    pub build_seconds: f64,
    pub times: RenderTimes,
    /// The paper's metric: total time / sensors, in milliseconds; the cache's sensors count too.
    pub sensor_time_ms: f64,
}

/// Where a render's time went. The phases are wall time on the host and add up to nearly the total; within
/// sensing, the host's own work and its waits are measured on the host, the device's by timestamps.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct RenderTimes {
    /// Global illumination: the radiance cache's first bounce (the direct light at its entries) and the
    /// others (0 without).
    pub cache_direct_seconds: f64,
    pub cache_bounces_seconds: f64,
    /// The G-buffer pass and its read-back.
    pub gbuffer_seconds: f64,
    /// The rounds of sensing and refinement.
    pub sensing_seconds: f64,
    /// Interpolation, filter, composition and the read-back of the image.
    pub post_seconds: f64,
    /// Host, within sensing: building views, recording and submitting batches.
    pub host_record_seconds: f64,
    /// Host, within sensing: waiting for batches to complete.
    pub host_wait_seconds: f64,
    /// Host, within sensing: the refinement's decisions between rounds, and its light hints.
    pub host_refine_seconds: f64,
    /// Host: finding the pixels to supersample and casting their samples (before sensing), their donors
    /// and visibilities (after).
    pub host_supersample_seconds: f64,
    /// Device, by timestamp queries: the culling pass (absent where nothing is culled), the sensor maps and
    /// the reduction (absent without timestamps; on CPU drivers clears may escape them).
    pub gpu_cull_seconds: Option<f64>,
    pub gpu_maps_seconds: Option<f64>,
    pub gpu_reduction_seconds: Option<f64>,
}

impl RenderTimes {
    pub(super) fn new(
        (gbuffer, sensing, post, refine, supersample): (Duration, Duration, Duration, Duration, Duration),
        batches: &BatchTimes,
        gi: Option<&super::GiStats>,
    ) -> Self {
        let (cache_direct_seconds, cache_bounces_seconds) = gi.map_or((0.0, 0.0), |g| g.seconds);
        Self {
            cache_direct_seconds,
            cache_bounces_seconds,
            gbuffer_seconds: gbuffer.as_secs_f64(),
            sensing_seconds: sensing.as_secs_f64(),
            post_seconds: post.as_secs_f64(),
            host_record_seconds: batches.host_record.as_secs_f64(),
            host_wait_seconds: batches.host_wait.as_secs_f64(),
            host_refine_seconds: refine.as_secs_f64(),
            host_supersample_seconds: supersample.as_secs_f64(),
            gpu_cull_seconds: batches.gpu_cull.map(|d| d.as_secs_f64()),
            gpu_maps_seconds: batches.gpu_maps.map(|d| d.as_secs_f64()),
            gpu_reduction_seconds: batches.gpu_reduction.map(|d| d.as_secs_f64()),
        }
    }
}

/// The renderer that made the render, as the statistics report it: a plain value, so that the statistics
/// know no renderer.
pub(super) struct Engine {
    pub sensor: crate::sensors::SensorKind,
    pub sensor_size: u32,
    pub strategy: StrategyKind,
    pub batch_size: u32,
    pub in_flight: u32,
    /// Whether the sensor maps were drawn from the scene's clusters.
    pub culled: bool,
    /// How long building the renderer took (the strategy's choice, pipelines).
    pub build: Duration,
    /// What the camera's sensors cost, batch by batch.
    pub batches: BatchTimes,
}

/// What the render loop counted.
pub(super) struct Counts {
    pub sensors_per_round: Vec<u64>,
    pub readback_bytes_per_round: Vec<u64>,
    pub fine_sensors: u64,
    pub interpolated_quads: u64,
    pub supersampled_pixels: u64,
    pub gi: Option<super::GiStats>,
}

impl RenderStats {
    pub(super) fn new(
        device: &Device,
        engine: Engine,
        size: ImageSize,
        frame: &FrameParams,
        counts: Counts,
        total: Duration,
        times: RenderTimes,
    ) -> Self {
        let total = total.as_secs_f64();
        let sensors: u64 = counts.sensors_per_round.iter().sum();
        let all_sensors =
            sensors + counts.fine_sensors + counts.gi.as_ref().map_or(0, |g| g.entries * g.bounces as u64);
        Self {
            device: device.adapter.name.clone(),
            driver: device.adapter.driver.clone(),
            sensor: engine.sensor.to_string(),
            strategy: engine.strategy,
            sensor_size: engine.sensor_size,
            width: size.width,
            height: size.height,
            tile: frame.tile,
            dradiance: frame.dradiance,
            indirect: frame.indirect.to_string(),
            filter_radius: frame.filter_radius,
            sensors,
            sensors_per_round: counts.sensors_per_round,
            readback_bytes_per_round: counts.readback_bytes_per_round,
            fine_sensors: counts.fine_sensors,
            interpolated_quads: counts.interpolated_quads,
            aa: frame.aa,
            supersampled_pixels: counts.supersampled_pixels,
            supersampled_share: counts.supersampled_pixels as f64 / (size.width as f64 * size.height as f64),
            gi: counts.gi,
            batch_size: engine.batch_size,
            batches: engine.batches.batches,
            culled: engine.culled,
            drawn_triangles_per_sensor: (engine.batches.drawn_triangles)
                .map(|t| if sensors > 0 { t as f64 / sensors as f64 } else { 0.0 }),
            selected_triangles_per_sensor: (engine.batches.selected_triangles)
                .map(|t| if sensors > 0 { t as f64 / sensors as f64 } else { 0.0 }),
            whole_clusters: engine.batches.whole_clusters,
            in_flight: engine.in_flight,
            total_seconds: total,
            build_seconds: engine.build.as_secs_f64(),
            times,
            sensor_time_ms: if all_sensors > 0 { 1e3 * total / all_sensors as f64 } else { 0.0 },
        }
    }
}
