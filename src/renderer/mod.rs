//! One render, end to end (docs/DESIGN.md §3): G-buffer → sensors on the grid → rounds of refinement, each
//! sensing its pixels in batches on the GPU (sensor maps + reduction, several batches in flight) →
//! interpolation → id-constrained filter → composition. The CPU decides where sensors go from the values
//! each round sensed; every image operation runs on the GPU.
//!
//! A [`Renderer`] is built for one scene and one kind and size of sensor ([`RendererBuilder`], which also
//! chooses the batching strategy); each [`Renderer::render`] then takes an image size and the per-render
//! [`FrameParams`].

mod batch;
mod build;
mod checks;
mod config;
pub mod detail;
mod estimate;
mod fine;
mod gaps;
mod gi;
mod points;
mod post;
mod preview;
mod probe;
mod progress;
mod resolve;
mod sensing;
mod stats;
mod targets;

use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context as _, Result};
use glam::{Vec3, Vec4};

pub use batch::BatchTimes;
use batch::{BatchRunner, Sensed, SensedMaps};
pub use build::{RendererBuilder, self_check, unsupported};
use checks::check_finite;
pub use config::{
    CLUSTER_MIN_TRIANGLES, CacheConfig, DEFAULT_IN_FLIGHT, Detail, RendererConfig, default_memory_budget,
};
pub use fine::FINE_FACTOR;
pub use gi::{BounceDone, CacheLevel, GiStats, LaterBounces};
use post::Post;
pub use probe::probe_pixels;
pub use progress::{Phase, Progress, Quiet, RoundDone, Snapshot};
pub use stats::{RenderStats, RenderTimes};

use crate::gbuffer::GBufferData;
use crate::gi::RadianceCache;
use crate::gpu_scene::GpuScene;
use crate::params::{FrameParams, Indirect};
use crate::passes::compose::ComposePass;
use crate::passes::filter::FilterPass;
use crate::passes::gbuffer::GBufferPass;
use crate::passes::interpolate::InterpolatePass;
use crate::passes::resolve::ResolvePass;
use crate::passes::sensor_maps::{Background, CacheRead, CkParams};
use crate::scene::bvh::Bvh;
use crate::scene::{Camera, ImageSize, Scene};
use crate::sensors::hints::LightPoint;
use crate::strategy::{Choice, StrategyKind};
use crate::supersample::ShadowPoints;
use crate::vk::{Device, transfer};

/// The GPU state for rendering one scene with one kind and size of sensor, reusable across renders.
pub struct Renderer {
    // Field order is drop order: the runner waits for its batches first.
    runner: BatchRunner,
    /// The finer sensors sensed again where a slit fell between the texels (`fine`), where the rd allows.
    fine: Option<BatchRunner>,
    /// The scene on the host and its triangles' BVH: the supersampling casts its samples' camera rays
    /// there, the light hints their shadow rays.
    host: Scene,
    bvh: Bvh,
    /// Points on the lights for the refinement's light hints (the exact estimator with lights; else `None`).
    light_points: Option<Vec<LightPoint>>,
    /// Points on the lights that supersampled samples cast shadow rays at, and sensed pixels whose sensors
    /// saw part of a light group (`gaps`; with `light_points`).
    shadow_points: Option<ShadowPoints>,
    /// The passes after the sensing: interpolation, filter, composition, the supersampled pixels' resolve.
    passes: PostPasses,
    gbuffer: GBufferPass,
    scene: GpuScene,
    /// The radiance cache's points and table, and the runner of its rows and later bounces (with
    /// `config.cache`).
    cache: Option<(RadianceCache, BatchRunner)>,
    /// How R is estimated: light groups, the exact interpolation, the cache's direct light, the offsets.
    estimate: estimate::Estimate,
    camera: Camera,
    /// The scene's diagonal: sensor offsets and near planes are fractions of it.
    scale: f32,
    config: RendererConfig,
    choice: Choice,
    /// How long building took: the strategy's self-checks and measurement (near nothing when cached), then
    /// pipelines and buffers. Not part of any render's own time.
    choice_time: Duration,
    /// How [`Detail::Auto`] was measured for this scene, where it was ([`detail`]).
    detail_probe: Option<detail::DetailProbe>,
    /// Whether the radiance cache holds a solution ([`Renderer::solve_cache`]).
    cache_solved: bool,
    /// Where [`Renderer::keep_cache`] asked for it: the frame's light the cache was last solved for
    /// (indirect model and background) and what solving it found.
    kept: Option<Option<(Indirect, Vec3, GiStats)>>,
    device: Arc<Device>,
}

/// The compute passes a render runs after its sensing (`post.rs`, `resolve.rs`).
struct PostPasses {
    interpolate: InterpolatePass,
    filter: FilterPass,
    compose: ComposePass,
    resolve: ResolvePass,
}

/// What a render produced.
pub struct RenderOutput {
    pub size: ImageSize,
    /// `Le + albedo·R`.
    pub image: Vec<Vec4>,
    /// R after interpolation and filtering (a supersampled pixel's: the mean over its samples on a surface);
    /// w says how it was obtained (see `gpu_types::radiance_state`).
    pub radiance: Vec<Vec4>,
    /// The G-buffer at the pixel centres, but where most of a supersampled pixel's samples show another
    /// surface than its centre: what the first of those sees.
    pub gbuffer: GBufferData,
    /// The pixels that were supersampled (`--aa on`), in increasing index.
    pub supersampled: Vec<u32>,
    pub stats: RenderStats,
}

impl Renderer {
    pub fn strategy(&self) -> StrategyKind {
        self.runner.kind()
    }

    /// Whether the sensor maps are drawn from the scene's clusters (see [`Detail`]).
    pub fn culled(&self) -> bool {
        self.runner.culled()
    }

    /// What the sensing since the last render or [`Renderer::sense_at`] cost (batches, times, triangles).
    pub fn batch_times(&self) -> BatchTimes {
        self.runner.times
    }

    /// How the level of detail was measured, where [`Detail::Auto`] measured it ([`detail`]).
    pub fn detail_probe(&self) -> Option<&detail::DetailProbe> {
        self.detail_probe.as_ref()
    }

    /// How the strategy was chosen.
    pub fn choice(&self) -> &Choice {
        &self.choice
    }

    /// How long [`RendererBuilder::build`] took: choosing the strategy, then creating pipelines (zero for
    /// [`RendererBuilder::build_unchecked`]).
    pub fn build_time(&self) -> Duration {
        self.choice_time
    }

    pub fn config(&self) -> &RendererConfig {
        &self.config
    }

    /// Sensors per batch.
    pub fn batch_size(&self) -> u32 {
        self.runner.capacity()
    }

    /// The G-buffer of the scene at `size` (e.g. to choose where to place probe sensors).
    pub fn gbuffer(&self, size: ImageSize) -> Result<GBufferData> {
        Ok(self.render_gbuffer(size)?.1)
    }

    /// The radiance cache's points and table, with global illumination.
    pub fn cache(&self) -> Option<&RadianceCache> {
        self.cache.as_ref().map(|(c, _)| c)
    }

    /// The radiance cache's values as the sensor maps read them (reflected radiance per entry, then the
    /// surface sides' fallbacks), after [`Renderer::solve_cache`]: for comparing the cache with the oracle.
    pub fn cache_values(&self) -> Result<Vec<Vec4>> {
        let cache = self.cache().context("this renderer has no radiance cache")?;
        transfer::read_buffer(&self.device, &self.scene.cache.values, cache.values_len())
    }

    /// What the sensor maps see on surfaces for `frame`: its ε, or the radiance cache once solved.
    fn ck(&self, frame: &FrameParams) -> CkParams {
        let solved = self.cache_solved && frame.indirect.bounces().is_some();
        let cache = if solved { CacheRead::Values } else { CacheRead::Off };
        CkParams { epsilon: frame.indirect.epsilon(), background: self.background(frame), cache }
    }

    /// What the sensors see where their rays leave the scene: the scene's sky map, else `frame`'s constant
    /// background.
    fn background(&self, frame: &FrameParams) -> Background {
        if self.host.sky.is_some() { Background::SkyMap } else { Background::Constant(frame.background) }
    }

    /// R sensed at `pixels` (surface pixels of the image at `size`), and the host time sensing took
    /// (views, recording, submissions, waits): for the strategy self-check and benchmarks.
    pub fn sense_at(&mut self, size: ImageSize, pixels: &[u32], frame: &FrameParams) -> Result<(Vec<Vec4>, Duration)> {
        let (_, g) = self.render_gbuffer(size)?;
        self.runner.bind(&SensedMaps::new(&self.device, size)?)?;
        let mut r = vec![Vec4::ZERO; g.surface.len()];
        let mut deliver = |b: &Sensed<'_>| b.pixels.iter().zip(b.results).for_each(|(&i, f)| r[i as usize] = f.r);
        let start = Instant::now();
        let ck = self.ck(frame);
        self.runner.sense(&g, pixels, ck, &mut deliver)?;
        self.runner.drain(&mut deliver)?;
        Ok((pixels.iter().map(|&i| r[i as usize]).collect(), start.elapsed()))
    }

    /// Runs the reduction alone over the last batch's first `count` sensors again (their maps are still in
    /// place after [`Renderer::sense_at`]); returns the time from submission to completion.
    pub fn time_reduction(&mut self, count: u32) -> Result<Duration> {
        self.runner.time_reduction(count)
    }

    /// Renders the scene at `size`.
    /// From now on [`Renderer::render`] solves the radiance cache only when the frame's indirect model or
    /// background differ from the last solution's (whose statistics it then reports again): the cache does
    /// not depend on the camera, so a viewer that moves it need not pay the bounces again.
    pub fn keep_cache(&mut self) {
        self.kept.get_or_insert(None);
    }

    /// Looks from `camera` from the next render on (the live viewer's moves). What the renderer built does
    /// not depend on the camera, nor does the radiance cache's solution.
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = camera;
        self.host.camera = camera;
    }

    pub fn render(&mut self, size: ImageSize, frame: &FrameParams, progress: &dyn Progress) -> Result<RenderOutput> {
        let start = Instant::now();
        // The cache first: the camera's sensors see it.
        let gi = self.cache_for(frame, progress)?;

        progress.phase(Phase::GBuffer);
        let gbuffer_start = Instant::now();
        let (targets, g, sky) = self.targets(size, frame)?;
        let gbuffer_time = gbuffer_start.elapsed();

        // Sensors on the grid, then rounds of refinement until no quad asks for more (paper §III-G).
        progress.phase(Phase::Sensing);
        let sensing_start = Instant::now();
        let mut rounds = self.sense_rounds(&g, &targets, frame, sky.as_deref(), progress)?;
        let sensing_time = sensing_start.elapsed();

        // Interpolation, filter, composition, then the supersampled pixels.
        progress.phase(Phase::Post);
        let post_start = Instant::now();
        let post = self.post(&targets, g, &mut rounds, frame, gi.is_some(), sky.is_some())?;
        let post_time = post_start.elapsed();
        check_finite(&post.image, size.width as usize, &self.device.adapter.driver)?;

        let supersample_time = rounds.supersample_time + post.supersample_time;
        let phases = (gbuffer_time, sensing_time, post_time, rounds.refine_time, supersample_time);
        let times = RenderTimes::new(phases, &self.runner.times, gi.as_ref());
        let counts = stats::Counts {
            sensors_per_round: rounds.per_round,
            readback_bytes_per_round: rounds.readback_per_round,
            fine_sensors: rounds.fine_sensors,
            interpolated_quads: rounds.refinement.interpolated().len() as u64,
            supersampled_pixels: post.supersampled.len() as u64,
            gi,
        };
        let stats = RenderStats::new(&self.device, self.engine(), size, frame, counts, start.elapsed(), times);
        let Post { image, radiance, gbuffer, mut supersampled, .. } = post;
        supersampled.sort_unstable();
        Ok(RenderOutput { size, image, radiance, gbuffer, supersampled, stats })
    }

    /// The radiance cache's solution for `frame`: the one kept from an earlier render where
    /// [`Renderer::keep_cache`] asked for it and the frame's light is the same, else solved now.
    fn cache_for(&mut self, frame: &FrameParams, progress: &dyn Progress) -> Result<Option<GiStats>> {
        let gi = match &self.kept {
            Some(Some((indirect, background, stats)))
                if self.cache_solved && *indirect == frame.indirect && *background == frame.background =>
            {
                Some(stats.clone())
            }
            _ => self.solve_cache(frame, progress)?,
        };
        if let (Some(kept), Some(stats)) = (&mut self.kept, &gi) {
            *kept = Some((frame.indirect, frame.background, stats.clone()));
        }
        Ok(gi)
    }

    /// What the statistics say of this renderer.
    fn engine(&self) -> stats::Engine {
        stats::Engine {
            sensor: self.config.sensor,
            sensor_size: self.config.sensor_size,
            strategy: self.strategy(),
            batch_size: self.batch_size(),
            in_flight: self.runner.in_flight(),
            culled: self.culled(),
            build: self.build_time(),
            batches: self.runner.times,
        }
    }

    /// The sensors' lift off their surface and their near plane: fractions of the scene's size.
    fn offsets(&self) -> (f32, f32) {
        self.estimate.offsets
    }
}
