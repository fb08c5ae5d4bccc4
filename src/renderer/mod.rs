//! One render, end to end (docs/DESIGN.md §3): G-buffer → sensors on the grid → rounds of refinement, each
//! sensing its pixels in batches on the GPU (sensor maps + reduction, several batches in flight) →
//! interpolation → id-constrained filter → composition. The CPU decides where sensors go from the values
//! each round sensed; every image operation runs on the GPU.
//!
//! A [`Renderer`] is built for one scene and one kind and size of sensor ([`RendererBuilder`], which also
//! chooses the batching strategy); each [`Renderer::render`] then takes an image size and the per-render
//! [`FrameParams`].

mod batch;
pub mod detail;
mod gi;
mod probe;
mod resolve;
mod stats;

use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context as _, Result, bail, ensure};
use ash::vk;
use glam::{Vec3, Vec4};
use gpu_allocator::MemoryLocation;

pub use batch::BatchTimes;
use batch::{BatchRunner, Sensed, SensedMaps};
pub use gi::{BounceDone, CacheLevel, GiStats, LaterBounces};
pub use probe::probe_pixels;
pub use stats::{RenderStats, RenderTimes};

use crate::cancel::Reason;
use crate::gbuffer::GBufferData;
use crate::gi::RadianceCache;
use crate::gi::entries::{IRRADIANCE_VARIATION, LIGHT_VARIATION};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::MAX_GROUPS;
use crate::light::groups::{Lights, luminance};
use crate::params::{Antialiasing, EstimatorKind, FrameParams, Indirect, Param, ParamError, RenderParams};
use crate::passes::compose::ComposePass;
use crate::passes::filter::FilterPass;
use crate::passes::gbuffer::{self, GBuffer, GBufferPass};
use crate::passes::interpolate::{self, InterpolatePass};
use crate::passes::resolve::ResolvePass;
use crate::passes::sensor_maps::{Background, CacheRead, CkParams, EmitterFronts, StrategyDesc, TEXEL_BYTES};
use crate::scene::bvh::Bvh;
use crate::scene::{Camera, ImageSize, Scene, Texture, texture};
use crate::sensors::SensorKind;
use crate::sensors::frame;
use crate::sensors::hints::{self, LightPoint};
use crate::sensors::layout::SensorLayout;
use crate::sensors::refine::{self, Refinement, Visibility};
use crate::strategy::{self, Cache, Choice, StrategyKind, StrategyRequest};
use crate::supersample::{self, ShadowPoints};
use crate::vk::{Access, Buffer, Device, barrier, transfer};

/// The steps of a render (docs/DESIGN.md §3), for progress displays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The G-buffer pass and its read-back.
    GBuffer,
    /// The radiance cache's bounces (global illumination).
    Bounces,
    /// Rounds of sensing and refinement.
    Sensing,
    /// Interpolation, filter, composition and the read-back of the image.
    Post,
}

/// A refinement round, judged: how much of the image is final. The total work of a render is not known up
/// front (each round decides the next), but pixels resolved (by sensing or interpolation) only grow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RoundDone {
    /// 1-based.
    pub round: u32,
    /// Sensors the round rendered.
    pub sensors: u64,
    /// Pixels whose value is decided, of `pixels`.
    pub resolved_pixels: u64,
    pub pixels: u64,
}

/// The render so far, after a round's sensors are done: for previews.
pub struct Snapshot {
    /// 1-based.
    pub round: u32,
    pub size: ImageSize,
    /// `Le + albedo·R` with R interpolated over every quad, judged or not, and not filtered.
    pub image: Vec<Vec4>,
}

/// Progress callbacks for long renders. Every method does nothing by default.
pub trait Progress {
    /// A step of the render begins.
    fn phase(&self, _phase: Phase) {}
    /// `n` more sensors will be rendered (once per round).
    fn queued(&self, _n: u64) {}
    /// `n` more sensors are done.
    fn done(&self, _n: u64) {}
    /// A round's results were judged.
    fn round(&self, _round: &RoundDone) {}
    /// The radiance cache's walk (`gi::reach`) begins a level: its sensors are [`Progress::queued`] next.
    fn cache_level(&self, _level: &CacheLevel) {}
    /// A bounce of the radiance cache is done (its sensors, if any, were [`Progress::queued`] and
    /// [`Progress::done`] in [`Phase::Bounces`]).
    fn bounce(&self, _bounce: &BounceDone) {}
    /// Whether [`Progress::snapshot`] should see round `round` (1-based): building one costs a pass over the
    /// image on the host.
    fn wants_snapshot(&self, _round: u32) -> bool {
        false
    }
    /// The image after a round, when [`Progress::wants_snapshot`] said so.
    fn snapshot(&self, _snapshot: &Snapshot) {}
    /// Whether to stop: asked before each batch of sensors (the radiance cache's and the camera's). The
    /// render then waits for the batches in flight and returns [`Cancelled`](crate::cancel::Cancelled).
    fn cancelled(&self) -> Option<Reason> {
        None
    }
}

/// No progress reporting.
pub struct Quiet;
impl Progress for Quiet {}

/// Batches in flight by default: one rendering while the host prepares the next.
pub const DEFAULT_IN_FLIGHT: u32 = 2;

/// Where [`Detail::Auto`] cannot measure (the camera sees nothing of the mesh), meshes of at least this many
/// triangles are drawn from their clusters: full detail costs per sensor in proportion to the triangles
/// (on lavapipe 36× the Cornell box at 10 000, the clusters 1.6×: docs/BENCHMARKS.md "Large meshes").
/// Otherwise every mesh from [`detail::DETAIL_PROBE_MIN_TRIANGLES`] on is drawn whichever way measures
/// faster on the device ([`detail`]); smaller ones at full detail.
pub const CLUSTER_MIN_TRIANGLES: usize = 5_000;

/// How finely the sensor maps draw the scene (docs/DESIGN.md §9). The camera's G-buffer and the emitters
/// are always full detail.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Detail {
    /// Clusters where they measure faster ([`detail`]: from [`detail::DETAIL_PROBE_MIN_TRIANGLES`]
    /// triangles on, where the device can draw them; unmeasured, from [`CLUSTER_MIN_TRIANGLES`]).
    #[default]
    Auto,
    /// Every view draws every triangle.
    Full,
    /// Clusters whatever the mesh's size, where the device can draw them.
    Clusters,
}

impl Detail {
    fn wants_clusters(self, triangles: usize) -> bool {
        match self {
            Detail::Auto => triangles >= CLUSTER_MIN_TRIANGLES,
            Detail::Full => false,
            Detail::Clusters => triangles > 0,
        }
    }
}

/// What a renderer is built for. These fix its pipelines and sensor maps; everything else is chosen per
/// render ([`FrameParams`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RendererConfig {
    /// How R is estimated: the exact estimator adds a zoom pair of layers per light group.
    pub estimator: EstimatorKind,
    pub sensor: SensorKind,
    /// rd: sensor map side in texels (see `params::RenderParams::sensor_size`).
    pub sensor_size: u32,
    /// Bytes for one batch's sensor maps and depth; `None`: [`default_memory_budget`].
    pub memory_budget: Option<u64>,
    /// At most this many sensors per batch, whatever the budget (the self-check's partial batches, tests).
    pub max_batch: Option<u32>,
    /// Batches in flight, ≥ 1 (each has its own maps: memory grows with it).
    pub in_flight: u32,
    pub strategy: StrategyRequest,
    pub detail: Detail,
    /// The radiance cache, for renders with global illumination (`None`: the renderer has none and renders
    /// the paper's ε only).
    pub cache: Option<CacheConfig>,
}

/// The radiance cache of a renderer for global illumination (docs/DESIGN.md §10).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct CacheConfig {
    /// Cells along the scene's longest side (`params::RenderParams::cache_resolution`).
    pub resolution: u32,
    /// rd of the sensors that measure what the entries see of the sky, and of the bounces after the first
    /// where the transport's rows would exceed `transport_budget` (the first measures the direct light and
    /// the rows at the renderer's own rd).
    pub sensor_size: u32,
    /// Host bytes the transport's rows may take (`gi::transport`), beyond which the bounces after the
    /// first are sensed again.
    pub transport_budget: u64,
}

impl CacheConfig {
    /// A cache of `resolution` cells along the scene's longest side, sensors of `sensor_size` where its
    /// bounces are sensed, and the default budget for the transport's rows.
    pub fn new(resolution: u32, sensor_size: u32) -> Self {
        Self { resolution, sensor_size, transport_budget: crate::gi::transport::DEFAULT_BUDGET }
    }

    /// The cache `params` ask for: with global illumination, of their resolution and sensor size.
    pub fn for_params(params: &RenderParams) -> Option<Self> {
        let (resolution, sensor_size) = (params.cache_resolution, params.cache_sensor_size);
        params.estimator.indirect.bounces().map(|_| Self::new(resolution, sensor_size))
    }
}

impl RendererConfig {
    /// The layers one sensor occupies with the scene's `lights`: the main layers, and with the exact
    /// estimator a zoom pair per light group.
    pub fn layout(&self, lights: &Lights) -> SensorLayout {
        let groups = match self.estimator {
            EstimatorKind::Exact => lights.groups.len() as u32,
            EstimatorKind::Paper => 0,
        };
        SensorLayout { kind: self.sensor, groups }
    }

    /// Bytes for one batch's maps and depth, sensors of `layout`: at most `max_batch` sensors' worth, else
    /// the memory budget.
    fn batch_budget(&self, device: &Device, layout: &SensorLayout) -> u64 {
        let per_sensor = layout.layers() as u64 * (self.sensor_size as u64).pow(2) * TEXEL_BYTES;
        let budget = self.memory_budget.unwrap_or_else(|| default_memory_budget(device, self.in_flight));
        self.max_batch.map_or(budget, |n| budget.min(n as u64 * per_sensor))
    }
}

/// Budget for one batch's sensor maps when none is given: together, the batches in flight use an eighth
/// of the device's largest local heap.
pub fn default_memory_budget(device: &Device, in_flight: u32) -> u64 {
    device.adapter.device_local_bytes / 8 / in_flight.max(1) as u64
}

/// Builds a [`Renderer`]: checks the settings against the device and chooses the batching strategy (its
/// self-check and, for `auto`, its measurement, cached in `cache`).
pub struct RendererBuilder<'a> {
    device: &'a Arc<Device>,
    scene: &'a Scene,
    config: RendererConfig,
    cache: Option<&'a mut Cache>,
    events: Option<&'a mut dyn FnMut(strategy::Event)>,
}

impl<'a> RendererBuilder<'a> {
    pub fn memory_budget(mut self, bytes: Option<u64>) -> Self {
        self.config.memory_budget = bytes;
        self
    }

    /// At most `sensors` per batch (e.g. to have full and partial batches on a small probe).
    pub fn max_batch(mut self, sensors: Option<u32>) -> Self {
        self.config.max_batch = sensors;
        self
    }

    pub fn in_flight(mut self, batches: u32) -> Self {
        self.config.in_flight = batches;
        self
    }

    pub fn strategy(mut self, request: StrategyRequest) -> Self {
        self.config.strategy = request;
        self
    }

    pub fn detail(mut self, detail: Detail) -> Self {
        self.config.detail = detail;
        self
    }

    pub fn estimator(mut self, estimator: EstimatorKind) -> Self {
        self.config.estimator = estimator;
        self
    }

    /// A radiance cache, for global illumination.
    pub fn radiance_cache(mut self, cache: Option<CacheConfig>) -> Self {
        self.config.cache = cache;
        self
    }

    /// Where self-checks and choices are remembered (default: nowhere, everything is measured afresh).
    pub fn cache(mut self, cache: &'a mut Cache) -> Self {
        self.cache = Some(cache);
        self
    }

    /// Receives what the strategy choice checked and measured.
    pub fn on_strategy_event(mut self, events: &'a mut dyn FnMut(strategy::Event)) -> Self {
        self.events = Some(events);
        self
    }

    /// Chooses the strategy and builds the renderer. Errors about a setting are [`ParamError`]s.
    pub fn build(self) -> Result<Renderer> {
        let Self { device, scene, config, cache, events } = self;
        check_size(device, &config)?;
        let layout = config.layout(&Lights::new(&scene.mesh));
        let budget = config.batch_budget(device, &layout);
        let mut own_cache = Cache::in_memory();
        let cache = cache.unwrap_or(&mut own_cache);
        let mut ignore = |_| ();
        let events = events.unwrap_or(&mut ignore);
        let started = Instant::now();
        let choice = {
            let mut prober = probe::ProbeRenderer::new(device, &config, budget, layout.groups);
            let (sensor, rd) = (config.sensor, config.sensor_size);
            strategy::choose(&mut prober, sensor, config.estimator, rd, budget, config.strategy, cache, events)?
        };
        let probe = detail::measure(device, scene, &config, choice.strategy, cache)?;
        let config = RendererConfig { detail: probe.as_ref().map_or(config.detail, |p| p.detail), ..config };
        let mut renderer = Renderer::new(device, scene, config, choice)?;
        renderer.choice_time = started.elapsed();
        renderer.detail_probe = probe;
        Ok(renderer)
    }

    /// Builds the renderer with `kind`, without its self-check: for the self-check itself, and for tests
    /// and benchmarks that compare strategies.
    pub fn build_unchecked(self, kind: StrategyKind) -> Result<Renderer> {
        check_size(self.device, &self.config)?;
        let choice = Choice { strategy: kind, reason: "unchecked".into() };
        Renderer::new(self.device, self.scene, self.config, choice)
    }
}

/// Self-checks `kind` against `per-sensor` on the probe (see [`crate::strategy`]), on `device`, for sensors
/// of `sensor` with the `estimator`.
pub fn self_check(
    device: &Arc<Device>,
    sensor: SensorKind,
    estimator: EstimatorKind,
    kind: StrategyKind,
) -> Result<strategy::CheckResult> {
    let config = RendererConfig {
        estimator,
        sensor,
        sensor_size: strategy::CHECK_RD,
        memory_budget: None,
        max_batch: None,
        in_flight: DEFAULT_IN_FLIGHT,
        strategy: StrategyRequest::Fixed(kind),
        detail: Detail::Full,
        cache: None,
    };
    let budget = default_memory_budget(device, DEFAULT_IN_FLIGHT);
    strategy::self_check(&mut probe::ProbeRenderer::new(device, &config, budget, 0), kind)
}

/// Why strategy `kind` cannot run on `device` for `scene` with sensors of `sensor` kind and size `rd` read by
/// `estimator`, if it cannot.
pub fn unsupported(
    device: &Device,
    scene: &Scene,
    (sensor, estimator, rd): (SensorKind, EstimatorKind, u32),
    kind: StrategyKind,
) -> Option<String> {
    let config = RendererConfig {
        estimator,
        sensor,
        sensor_size: rd,
        memory_budget: None,
        max_batch: None,
        in_flight: DEFAULT_IN_FLIGHT,
        strategy: StrategyRequest::Fixed(kind),
        detail: Detail::Full,
        cache: None,
    };
    let layout = config.layout(&Lights::new(&scene.mesh));
    let desc = StrategyDesc { layout, fronts: fronts(estimator), rd, budget: config.batch_budget(device, &layout) };
    crate::passes::sensor_maps::unsupported(kind, device, &desc)
}

/// What emitter fronts leave in the maps with `estimator`.
fn fronts(estimator: EstimatorKind) -> EmitterFronts {
    match estimator {
        EstimatorKind::Exact => EmitterFronts::Group,
        EstimatorKind::Paper => EmitterFronts::Emission,
    }
}

/// Never an image of NaN with success: whatever produced one (a driver, a bug) is an error, before anything
/// is written.
fn check_finite(image: &[Vec4], width: usize, driver: &str) -> Result<()> {
    let non_finite = |v: &&Vec4| !v.truncate().is_finite();
    if let Some(first) = image.iter().position(|v| non_finite(&v)) {
        bail!(
            "the image has {} NaN or infinite pixel(s), the first at x {}, y {}: this is a bug in sensorlight or the \
             Vulkan driver ({driver}); nothing was written",
            image.iter().filter(non_finite).count(),
            first % width,
            first / width
        );
    }
    Ok(())
}

/// The radiance cache's table and values against the device: at most an eighth of its local memory (as the
/// batches in flight together), before anything is uploaded.
fn check_cache_size(device: &Device, bytes: u64, resolution: u32) -> Result<()> {
    let most = device.adapter.device_local_bytes / 8;
    if bytes > most || bytes > device.adapter.limits.max_storage_buffer_range as u64 {
        let problem = format!(
            "{resolution} gives a radiance cache of at least {:.0} MiB, more than this device allows ({:.0} MiB, an \
             eighth of its memory, in storage buffers of at most {:.0} MiB); use fewer cells",
            bytes as f64 / (1 << 20) as f64,
            most as f64 / (1 << 20) as f64,
            device.adapter.limits.max_storage_buffer_range as f64 / (1 << 20) as f64
        );
        return Err(ParamError::new(Param::CacheResolution, problem).into());
    }
    Ok(())
}

/// The scene's textures against the device, before anything is uploaded: their levels together in one
/// storage buffer, at most a quarter of its local memory.
fn check_textures(device: &Device, textures: &[Texture]) -> Result<()> {
    let bytes = texture::gpu_bytes(textures);
    let most = (device.adapter.device_local_bytes / 4).min(device.adapter.limits.max_storage_buffer_range as u64);
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    let largest = textures.iter().max_by_key(|t| t.texel_count());
    let largest = largest.map_or(String::new(), |t| {
        let own = texture::gpu_bytes(std::slice::from_ref(t));
        format!(" (the largest, {}, is {} × {}: {:.0} MiB)", t.name, t.width(), t.height(), mib(own))
    });
    ensure!(
        bytes <= most,
        "the scene's {} texture(s) need {:.0} MiB with their mipmaps{largest}, more than this device allows ({:.0} \
         MiB: a quarter of its memory, in one storage buffer); use smaller images",
        textures.len(),
        mib(bytes),
        mib(most)
    );
    Ok(())
}

/// The sensor size against the device's largest image and framebuffer side.
fn check_size(device: &Device, config: &RendererConfig) -> Result<()> {
    let limits = &device.adapter.limits;
    let max = limits.max_image_dimension_2d.min(limits.max_framebuffer_width).min(limits.max_framebuffer_height);
    if let Some(problem) = config.sensor.size_problem(config.sensor_size, max) {
        return Err(ParamError::new(Param::SensorSize, problem).into());
    }
    match config.cache.and_then(|c| config.sensor.size_problem(c.sensor_size, max)) {
        Some(problem) => Err(ParamError::new(Param::CacheSensorSize, problem).into()),
        None => Ok(()),
    }
}

/// The GPU state for rendering one scene with one kind and size of sensor, reusable across renders.
pub struct Renderer {
    // Field order is drop order: the runner waits for its batches first.
    runner: BatchRunner,
    /// The scene on the host and its triangles' BVH: the supersampling casts its samples' camera rays
    /// there, the light hints their shadow rays.
    host: Scene,
    bvh: Bvh,
    /// Points on the lights for the refinement's light hints (the exact estimator with lights; else `None`).
    light_points: Option<Vec<LightPoint>>,
    /// Points on the lights that supersampled samples cast shadow rays at (with `light_points`).
    shadow_points: Option<ShadowPoints>,
    interpolate: InterpolatePass,
    filter: FilterPass,
    compose: ComposePass,
    resolve: ResolvePass,
    gbuffer: GBufferPass,
    scene: GpuScene,
    /// The radiance cache's points and table, and the runner of its rows and later bounces (with
    /// `config.cache`).
    cache: Option<(RadianceCache, BatchRunner)>,
    /// Whether the cache's direct light is measured by shadow rays (`gi::DirectByRays`): light groups of at
    /// most one emitter chunk; else by the render's sensors.
    direct_by_rays: bool,
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

/// What one render writes on the GPU; dropped when the render returns (all its work waited for).
struct Targets {
    gbuffer: GBuffer,
    /// R and its indirect part, shared with the batches in flight, which keep them alive until they complete.
    sensed: SensedMaps,
    /// Which light points each pixel sees, 64 bits a pixel, for the filter (zeros without hints).
    light_masks: Buffer,
    /// R filtered; its indirect part filtered at R's radius and at its own; what the image is composed from.
    filtered: Buffer,
    indirect_at_r: Buffer,
    indirect_own: Buffer,
    composed: Buffer,
    image: Buffer,
    /// Under a sky map, the sky each pixel shows where no surface is (`vec4`; one unread texel without).
    sky: Buffer,
}

impl Renderer {
    /// A builder for `scene` with sensors of `sensor` kind and size `sensor_size`, `auto` strategy, the
    /// default budget and batches in flight.
    pub fn builder<'a>(
        device: &'a Arc<Device>,
        scene: &'a Scene,
        sensor: SensorKind,
        sensor_size: u32,
    ) -> RendererBuilder<'a> {
        let config = RendererConfig {
            estimator: EstimatorKind::default(),
            sensor,
            sensor_size,
            memory_budget: None,
            max_batch: None,
            in_flight: DEFAULT_IN_FLIGHT,
            strategy: StrategyRequest::Auto,
            detail: Detail::Auto,
            cache: None,
        };
        RendererBuilder { device, scene, config, cache: None, events: None }
    }

    fn new(device: &Arc<Device>, scene: &Scene, config: RendererConfig, choice: Choice) -> Result<Self> {
        check_textures(device, &scene.mesh.textures)?;
        let scale = scene.mesh.scale();
        let hierarchy = cluster_hierarchy(device, scene, config.detail);
        let lights = Lights::new(&scene.mesh);
        let layout = config.layout(&lights);
        let (bias, near) = (frame::BIAS * scale, frame::NEAR * scale);
        // The scene's triangles and points on its lights: the refinement's light hints, and where the radiance
        // cache's pieces are halved.
        let bvh = Bvh::of_mesh(&scene.mesh);
        let mut light_points = (layout.groups > 0).then(|| hints::light_points(&lights));
        // A sky map's bright patches too: its shadows split quads as the lights' do (the shares, by group,
        // ignore these points).
        if let Some(sky) = &scene.sky {
            let points = light_points.get_or_insert_with(Vec::new);
            points.extend(hints::sky_points(sky, &scene.mesh.bounds, points.len()));
        }
        let shadow_points = (layout.groups > 0).then(|| ShadowPoints::new(&lights));
        // The cache's direct light by shadow rays and the closed form, where the closed form is cheap (as for
        // the exact interpolation).
        let direct_by_rays = layout.groups > 0 && lights.emitters.len() <= crate::gpu_types::EMITTER_CHUNK as usize;
        if let Some(c) = config.cache {
            check_cache_size(device, RadianceCache::bytes_at_least(&scene.mesh, c.resolution), c.resolution)?;
        }
        let cache = config.cache.map(|c| {
            let lod = hierarchy.as_ref().map(lod_triangles).unwrap_or_default();
            // The lights' irradiance in closed form where it is cheap (as for the exact interpolation).
            let few = lights.emitters.len() <= crate::gpu_types::EMITTER_CHUNK as usize;
            let irradiance = |p: Vec3, n: Vec3| lights.unoccluded(p + n * bias, n).iter().map(|&e| luminance(e)).sum();
            let varies = |points: &[Vec3], n: Vec3| {
                let Some(hinted) = &light_points else { return false };
                [n, -n].iter().any(|&n| {
                    let seen = points.iter().map(|&p| hints::mask(&bvh, hinted, (p, n), bias, near).count_ones());
                    let (lo, hi) = seen.fold((u32::MAX, 0), |(lo, hi), s| (lo.min(s), hi.max(s)));
                    (hi - lo) as f32 > LIGHT_VARIATION * hinted.len() as f32
                        || few && {
                            let e = points.iter().map(|&p| irradiance(p, n));
                            let (dim, bright) = e.fold((f32::MAX, 0.0f32), |(lo, hi), e: f32| (lo.min(e), hi.max(e)));
                            bright > IRRADIANCE_VARIATION * dim
                        }
                })
            };
            RadianceCache::build(&scene.mesh, c.resolution, &lod, Some(&varies))
        });
        if let (Some(c), Some(config)) = (&cache, config.cache) {
            check_cache_size(device, c.bytes(), config.resolution)?;
        }
        let gpu_scene = GpuScene::upload(device, scene, hierarchy.as_ref(), cache.as_ref())?;
        let mut budget = config.batch_budget(device, &layout);
        let offsets = (bias, near);
        // The cache's later bounces: its main layers only, no zoom views (their direct light is the first
        // bounce's), at their own rd, in a quarter of the budget (no more than all its entries need).
        let cache = match (cache, config.cache) {
            (Some(points), Some(c)) => {
                let layout = SensorLayout { kind: config.sensor, groups: 0 };
                let all = points.entries.len().max(1) as u64 * layout.layers() as u64 * (c.sensor_size as u64).pow(2);
                let quarter = (budget / 4).min(all * TEXEL_BYTES);
                budget -= quarter;
                let desc = StrategyDesc { layout, fronts: EmitterFronts::Group, rd: c.sensor_size, budget: quarter };
                let runner = BatchRunner::new(device, &gpu_scene, choice.strategy, desc, config.in_flight, offsets)?;
                Some((points, runner.with_rows()?))
            }
            _ => None,
        };
        let desc = StrategyDesc { layout, fronts: fronts(config.estimator), rd: config.sensor_size, budget };
        Ok(Self {
            host: scene.clone(),
            bvh,
            light_points,
            shadow_points,
            runner: {
                let runner = BatchRunner::new(device, &gpu_scene, choice.strategy, desc, config.in_flight, offsets)?;
                // The radiance cache's first bounce reads the transport's rows from the render's maps where
                // no shadow rays give its direct light (`gi::solve`).
                if cache.is_some() && !direct_by_rays { runner.with_rows()? } else { runner }
            },
            interpolate: InterpolatePass::new(device)?,
            filter: FilterPass::new(device)?,
            compose: ComposePass::new(device)?,
            resolve: ResolvePass::new(device)?,
            gbuffer: GBufferPass::new(device, &gpu_scene)?,
            scene: gpu_scene,
            cache,
            direct_by_rays,
            camera: scene.camera,
            scale,
            config,
            choice,
            choice_time: Duration::ZERO,
            detail_probe: None,
            cache_solved: false,
            kept: None,
            device: device.clone(),
        })
    }

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

    /// The G-buffer at `size`, on the GPU and on the host.
    fn render_gbuffer(&self, size: ImageSize) -> Result<(GBuffer, GBufferData)> {
        let near = gbuffer::NEAR * self.scale;
        let gpu = self.gbuffer.render(&self.device, &self.scene, &self.camera, size, near)?;
        let host = gpu.read_back(&self.device)?;
        Ok((gpu, host))
    }

    /// The G-buffer of the scene at `size` (e.g. to choose where to place probe sensors).
    pub fn gbuffer(&self, size: ImageSize) -> Result<GBufferData> {
        Ok(self.render_gbuffer(size)?.1)
    }

    /// Senses the radiance cache's bounces for `frame`'s global illumination, leaving the cache for the
    /// sensor maps that follow ([`Renderer::render`] does this itself; [`Renderer::sense_at`] then sees it).
    /// An error if the renderer was built without a cache.
    pub fn solve_cache(&mut self, frame: &FrameParams, progress: &dyn Progress) -> Result<Option<GiStats>> {
        self.cache_solved = false;
        let Some(bounces) = frame.indirect.bounces() else { return Ok(None) };
        let background = self.background(frame);
        let (cache, later) = self.cache.as_mut().context(
            "this renderer was built without a radiance cache (RendererBuilder::radiance_cache): it renders the \
             paper's ε only",
        )?;
        // Only the entries light reaches are sensed: the walk starts at the emitters' entries, and where
        // rays that leave the scene carry light, at the entries that see out.
        let distant_lights = self.host.mesh.local_triangles().len() < self.host.mesh.triangles.len();
        let sky = !background.is_black() || distant_lights;
        let bias = frame::BIAS * self.scale;
        let seeds = crate::gi::reach::seeds(cache, &self.host.mesh, &self.bvh, sky, bias);
        let runners = gi::Runners { first: &mut self.runner, later };
        let budget = self.config.cache.map_or(crate::gi::transport::DEFAULT_BUDGET, |c| c.transport_budget);
        let light = (bounces, background, budget);
        // Where the light hints have points on the lights, an uneven piece's direct light is measured by
        // shadow rays from the points spread over it rather than by sensors there.
        let (lights, bvh, near) = (&self.scene.lights, &self.bvh, frame::NEAR * self.scale);
        let bits = hints::group_bits(lights);
        let bits = &bits;
        let direct = |points: &[LightPoint], p: Vec3, n: Vec3| -> Vec3 {
            let (facing, seen) = hints::masks(bvh, points, (p, n), bias, near);
            let e = lights.unoccluded(p + n * bias, n);
            let share = |g: u64| match (facing & g).count_ones() {
                0 => 1.0,
                f => (seen & g).count_ones() as f32 / f as f32,
            };
            bits.iter().zip(e).map(|(&g, e)| e * share(g)).sum::<Vec3>() / std::f32::consts::PI
        };
        let points = self.light_points.as_deref().filter(|_| self.direct_by_rays);
        let rays = points.map(|points| move |p: Vec3, n: Vec3| direct(points, p, n));
        let rays = rays.as_ref().map(|f| f as gi::DirectByRays<'_>);
        let stats = gi::solve(&self.device, runners, (cache, &self.scene.cache, seeds), light, rays, progress)?;
        self.cache_solved = true;
        Ok(Some(stats))
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
        let device = self.device.clone();
        let pixels = size.width as usize * size.height as usize;
        // The cache first: the camera's sensors see it.
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

        progress.phase(Phase::GBuffer);
        let gbuffer_start = Instant::now();
        let (gpu_gbuffer, g) = self.render_gbuffer(size)?;
        // Under a sky map, the sky each pixel shows where no surface is: over its square (64 points) or at
        // its centre, as the pixel is.
        let side = if frame.aa == Antialiasing::On { 8 } else { 1 };
        let sky = self.host.sky.as_ref().map(|sky| sky.pixels(&self.host.camera, size, side));
        let targets = Targets {
            gbuffer: gpu_gbuffer,
            sensed: SensedMaps::new(&device, size)?,
            light_masks: {
                let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
                Buffer::new(&device, "light masks", 8 * pixels as u64, usage, MemoryLocation::GpuOnly)?
            },
            filtered: map_buffer(&device, "filtered radiance map", size)?,
            indirect_at_r: map_buffer(&device, "indirect map at R's filter", size)?,
            indirect_own: map_buffer(&device, "indirect map, filtered", size)?,
            composed: map_buffer(&device, "composed radiance map", size)?,
            image: map_buffer(&device, "final image", size)?,
            sky: {
                let texels: Vec<Vec4> = match &sky {
                    Some(sky) => sky.iter().map(|s| s.extend(0.0)).collect(),
                    None => vec![Vec4::ZERO],
                };
                transfer::upload(&device, "sky pixels", &texels, vk::BufferUsageFlags::STORAGE_BUFFER)?
            },
        };
        device.submit_and_wait(|enc| {
            enc.fill(&targets.sensed.radiance, 0);
            enc.fill(&targets.sensed.indirect, 0);
            enc.fill(&targets.light_masks, 0);
            Ok(())
        })?;
        self.runner.bind(&targets.sensed)?;
        let gbuffer_time = gbuffer_start.elapsed();

        // Sensors on the grid, then rounds of refinement until no quad asks for more (paper §III-G). The
        // host keeps R only where it sensed: that is all the refinement reads.
        progress.phase(Phase::Sensing);
        let sensing_start = Instant::now();
        let ck = self.ck(frame);
        let (refinement, mut pending) = Refinement::start(&g, frame.tile, frame.dradiance);
        let t = Instant::now();
        let (bias, near) = (frame::BIAS * self.scale, frame::NEAR * self.scale);
        let masks = self.light_points.as_ref().map(|points| hints::hints(&self.bvh, points, &g, bias, near));
        if let Some(masks) = &masks {
            transfer::write_buffer(&device, &targets.light_masks, masks)?;
        }
        let hint_time = t.elapsed();
        // Which pixels take sub-pixel samples, and what the samples see (docs/DESIGN.md §11).
        let t = Instant::now();
        let bits = self.light_points.as_ref().map(|_| hints::group_bits(&self.scene.lights)).unwrap_or_default();
        let plan = match frame.aa {
            Antialiasing::On => {
                let flags = supersample::detect(&self.host, &g, masks.as_deref().unwrap_or(&[]), &bits);
                supersample::plan(&self.host, &self.bvh, &g, &flags)
            }
            Antialiasing::Off => supersample::Plan::default(),
        };
        let mut supersample_time = t.elapsed();
        let mut refinement = match masks {
            Some(masks) => refinement.with_hints(masks),
            None => refinement,
        };
        let mut r = vec![Vec4::ZERO; pixels];
        let exact = self.runner.measures_lights();
        let mut visibility: Vec<Visibility> = if exact { vec![[-1.0; MAX_GROUPS]; pixels] } else { Vec::new() };
        // With the exact estimator over the hemisphere (a domain the same whatever a sensor's turn), the
        // interpolation computes each light group's unoccluded light per pixel and interpolates only the
        // visibilities and the rest of R (`interpolate_exact.comp`), so the refinement judges those. A pixel
        // loops over every emitter there, so only up to one emitter chunk's worth: with thousands of emissive
        // triangles that loop would cost more per pixel than a sensor's emitter pass (docs/ACCURACY.md).
        let few_emitters = self.scene.lights.emitters.len() <= crate::gpu_types::EMITTER_CHUNK as usize;
        let exact_interpolation = exact && self.config.sensor == SensorKind::Hemicube && few_emitters;
        let mut rest = if exact_interpolation { vec![Vec4::ZERO; pixels] } else { Vec::new() };
        let (mut per_round, mut readback_per_round) = (Vec::new(), Vec::new());
        let mut refine_time = hint_time;
        loop {
            if !pending.is_empty() {
                progress.queued(pending.len() as u64);
                let read_before = self.runner.times.readback_bytes;
                let mut deliver = |b: &Sensed<'_>| {
                    for (&i, f) in b.pixels.iter().zip(b.results) {
                        r[i as usize] = f.r;
                        if exact {
                            visibility[i as usize] = f.visibility;
                        }
                        if exact_interpolation {
                            rest[i as usize] = f.rest;
                        }
                    }
                    progress.done(b.pixels.len() as u64);
                };
                self.runner.sense_or_stop(&g, &pending, ck, &mut deliver, &|| progress.cancelled())?;
                self.runner.drain(&mut deliver)?;
                per_round.push(pending.len() as u64);
                readback_per_round.push(self.runner.times.readback_bytes - read_before);
                let round = per_round.len() as u32;
                if progress.wants_snapshot(round) {
                    let light = exact_interpolation.then(|| PreviewLight {
                        visibility: &visibility,
                        rest: &rest,
                        lights: &self.scene.lights,
                        bias,
                    });
                    let image = preview(&g, &r, &refinement, (frame.background, sky.as_deref()), light);
                    progress.snapshot(&Snapshot { round, size, image });
                }
            }
            if refinement.is_finished() {
                break;
            }
            let t = Instant::now();
            pending = refinement.step(&r, &visibility, &rest);
            refine_time += t.elapsed();
            progress.round(&RoundDone {
                round: per_round.len() as u32,
                sensors: per_round.last().copied().unwrap_or(0),
                resolved_pixels: pixels as u64 - refinement.unresolved_pixels(),
                pixels: pixels as u64,
            });
        }
        let sensing_time = sensing_start.elapsed();

        // Interpolation, filter, composition: one submission.
        progress.phase(Phase::Post);
        let post_start = Instant::now();
        let (sensed, t) = (&targets.sensed, &targets);
        let quads = refinement.interpolated();
        let corner_visibility =
            if exact_interpolation { refine::corner_visibility(&visibility, size.width, quads) } else { Vec::new() };
        let sensed_pixel = |i: usize| refinement.is_sensed(i);
        let exact_light = exact_interpolation.then(|| interpolate::Exact {
            sensed: &sensed_pixel,
            corner_visibility: &corner_visibility,
            gbuffer: &targets.gbuffer,
            scene: &self.scene,
            bias,
        });
        self.interpolate.bind(&device, quads, [&sensed.radiance, &sensed.indirect], exact_light)?;
        let (ids, masks) = (&t.gbuffer.surface, &t.light_masks);
        // The indirect part apart: with global illumination and the exact estimator (whose main layers hold
        // only it), where its radius is R's own it is not (R's filter already does it).
        let apart =
            gi.is_some() && self.runner.measures_lights() && frame.indirect_filter_radius != frame.filter_radius;
        self.filter.bind(&device, 0, (&sensed.radiance, &t.filtered), ids, masks);
        self.filter.bind(&device, 1, (&sensed.indirect, &t.indirect_at_r), ids, masks);
        self.filter.bind(&device, 2, (&sensed.indirect, &t.indirect_own), ids, masks);
        self.compose.bind(
            &device,
            [&t.filtered, &t.indirect_at_r, &t.indirect_own],
            [&t.image, &t.composed],
            &t.gbuffer,
            &t.sky,
        );
        device.submit_and_wait(|enc| {
            barrier::global(enc, &[Access::ComputeWrite, Access::TransferWrite], &[Access::ComputeWrite]);
            self.interpolate.record(enc, size);
            barrier::global(enc, &[Access::ComputeWrite], &[Access::ComputeWrite]);
            self.filter.record(enc, 0, size, frame.filter_radius);
            if apart {
                self.filter.record(enc, 1, size, frame.filter_radius);
                self.filter.record(enc, 2, size, frame.indirect_filter_radius);
            }
            barrier::global(enc, &[Access::ComputeWrite], &[Access::ComputeWrite]);
            self.compose.record(enc, size, apart, sky.is_none().then_some(frame.background));
            Ok(())
        })?;
        // The supersampled pixels, a slice at a time: their samples' R from their donors, the mean over each.
        let start_samples = Instant::now();
        let everywhere = (exact_interpolation && frame.aa == Antialiasing::On).then(|| {
            refine::visibility_everywhere(&visibility, size.width, refinement.interpolated(), |i| {
                refinement.is_sensed(i)
            })
        });
        let light = everywhere.as_deref().map(|v| (v, refinement.hints(), bits.as_slice()));
        let offsets = (bias, near);
        let (mut resolved, mut majorities) =
            self.resolve_supersampled(&plan, (&g, &targets), light, offsets, frame.background)?;
        let mut radiance = transfer::read_buffer::<Vec4>(&device, &targets.composed, pixels)?;
        // Then where the light ends inside a pixel, which only the light as sensed and resolved shows (with
        // the exact light only: the samples' shadow rays place the end, `supersample::shadow`).
        let mut plan = plan;
        if light.is_some() {
            let mut seen = radiance.clone();
            for (&i, r) in plan.pixels.iter().zip(&resolved) {
                seen[i as usize] = *r;
            }
            let ends = supersample::plan(&self.host, &self.bvh, &g, &supersample::light_ends(&g, &seen, &plan.pixels));
            let (more, more_majorities) =
                self.resolve_supersampled(&ends, (&g, &targets), light, offsets, frame.background)?;
            (resolved, majorities) = ([resolved, more].concat(), [majorities, more_majorities].concat());
            plan.append(ends);
        }
        supersample_time += start_samples.elapsed();
        let image = transfer::read_buffer::<Vec4>(&device, &targets.image, pixels)?;
        // The AOVs of a supersampled pixel: R over its samples on a surface; the G-buffer's of the surface
        // most of them show.
        let mut g = g;
        for ((&i, r), majority) in plan.pixels.iter().zip(&resolved).zip(majorities) {
            let i = i as usize;
            radiance[i] = r.truncate().extend(radiance[i].w);
            if let Some(v) = majority {
                (g.position[i], g.normal[i], g.albedo[i], g.emission[i], g.surface[i]) =
                    (v.position, v.normal, v.albedo, v.emission, v.surface);
            }
        }
        let post_time = post_start.elapsed();
        check_finite(&image, size.width as usize, &device.adapter.driver)?;

        let phases = (gbuffer_time, sensing_time, post_time, refine_time, supersample_time);
        let times = RenderTimes::new(phases, &self.runner.times, gi.as_ref());
        let stats = RenderStats::new(
            &self.device,
            self,
            size,
            frame,
            stats::Counts {
                sensors_per_round: per_round,
                readback_bytes_per_round: readback_per_round,
                interpolated_quads: refinement.interpolated().len() as u64,
                supersampled_pixels: plan.pixels.len() as u64,
                gi,
            },
            start.elapsed(),
            times,
        );
        let mut supersampled = plan.pixels;
        supersampled.sort_unstable();
        Ok(RenderOutput { size, image, radiance, gbuffer: g, supersampled, stats })
    }
}

/// What the exact interpolation's CPU twin needs for a preview: per pixel, the sensed visibilities and R's
/// rest; the lights and the sensors' lift.
struct PreviewLight<'a> {
    visibility: &'a [Visibility],
    rest: &'a [Vec4],
    lights: &'a Lights,
    bias: f32,
}

/// The image so far on the host, from the R sensed (`r`, where `refinement` sensed) interpolated over every
/// quad as the render's interpolation does (with `light`, the exact interpolation's CPU twin): unfiltered,
/// and only ever a preview (the render's own image comes from the GPU passes).
fn preview(
    g: &GBufferData,
    r: &[Vec4],
    refinement: &Refinement,
    (background, sky): (glam::Vec3, Option<&[glam::Vec3]>),
    light: Option<PreviewLight<'_>>,
) -> Vec<Vec4> {
    use crate::gpu_types::radiance_state::SENSED;
    let sensed = |v: &[Vec4]| -> Vec<Vec4> {
        (v.iter().enumerate())
            .map(|(i, v)| if refinement.is_sensed(i) { v.truncate().extend(SENSED) } else { Vec4::ZERO })
            .collect()
    };
    let mut radiance = sensed(r);
    let quads = refinement.coverage();
    match light {
        Some(l) => {
            let corners = refine::corner_visibility(l.visibility, g.size.width, &quads);
            let rest = sensed(l.rest);
            refine::interpolate_exact_cpu((&mut radiance, &rest), &corners, (g, l.lights, l.bias), &quads);
        }
        None => refine::interpolate_cpu(&mut radiance, g.size.width, &quads),
    }
    (g.surface.iter().zip(&g.emission).zip(&g.albedo).zip(&radiance).enumerate())
        .map(|(i, (((&id, le), kd), r))| match id {
            crate::scene::NO_SURFACE => sky.map_or(background, |s| s[i]).extend(0.0),
            _ => (le.truncate() + kd.truncate() * r.truncate()).extend(1.0),
        })
        .collect()
}

/// The cluster hierarchy to draw the sensor maps from, if `detail` asks for one for this mesh and the device
/// can draw from it (read from the cluster cache, else built and cached; the cache is advisory).
fn cluster_hierarchy(device: &Device, scene: &Scene, detail: Detail) -> Option<crate::clusters::ClusterMesh> {
    if !detail.wants_clusters(scene.mesh.triangles.len())
        || crate::passes::sensor_maps::culling_unsupported(device, 0).is_some()
    {
        return None;
    }
    let dir = crate::clusters::cache::default_dir();
    let (hierarchy, _cache_note) = crate::clusters::cache::load_or_build(&scene.mesh, dir.as_deref());
    let bound = crate::clusters::max_selected(&hierarchy) as u32;
    crate::passes::sensor_maps::culling_unsupported(device, bound).is_none().then_some(hierarchy)
}

/// The triangles of every coarser level of `hierarchy` (what culled sensor maps may draw instead of the
/// mesh's own), for the radiance cache's keys.
fn lod_triangles(hierarchy: &crate::clusters::ClusterMesh) -> Vec<([glam::Vec3; 3], crate::scene::SurfaceId)> {
    let p = |i: u32| glam::Vec3::from(hierarchy.positions[i as usize]);
    (hierarchy.clusters.iter().filter(|k| !k.is_full_detail()))
        .flat_map(|k| hierarchy.triangles_of(k))
        .map(|t| (t.map(p), hierarchy.vertex_surface[t[0] as usize]))
        .collect()
}

impl SensedMaps {
    /// Both maps for an image of `size`.
    fn new(device: &Arc<Device>, size: ImageSize) -> Result<Self> {
        Ok(Self {
            radiance: Arc::new(map_buffer(device, "radiance map", size)?),
            indirect: Arc::new(map_buffer(device, "indirect map", size)?),
        })
    }
}

/// A radiance-map-sized buffer of `vec4` per pixel, written by compute passes and read back.
fn map_buffer(device: &Arc<Device>, name: &str, size: ImageSize) -> Result<Buffer> {
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    Buffer::new(device, name, size.width as u64 * size.height as u64 * 16, usage, MemoryLocation::GpuOnly)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_with_nan_or_inf_is_an_error_naming_the_first() {
        let mut image = vec![Vec4::ONE; 6];
        assert!(check_finite(&image, 3, "d").is_ok());
        image[4].y = f32::NAN;
        image[5].x = f32::INFINITY;
        let message = check_finite(&image, 3, "d").unwrap_err().to_string();
        assert!(message.contains("2 NaN or infinite pixel(s), the first at x 1, y 1"), "{message}");
        image[4].w = 0.0;
        image[4].y = 0.0;
        image[5] = Vec4::new(1.0, 1.0, 1.0, f32::NAN);
        assert!(check_finite(&image, 3, "d").is_ok(), "alpha is not part of the image");
    }
}
