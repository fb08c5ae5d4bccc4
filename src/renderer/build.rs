//! Building a [`Renderer`]: the settings checked against the device, the batching strategy chosen (its
//! self-check, `auto`'s measurement), the level of detail measured, then the scene, the radiance cache's
//! pieces and every pass's pipeline made once.

use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use glam::Vec3;

use super::batch::BatchRunner;
use super::checks::{check_cache_size, check_size, check_textures};
use super::config::{CacheConfig, DEFAULT_IN_FLIGHT, Detail, RendererConfig, default_memory_budget};
use super::estimate::Estimate;
use super::{PostPasses, Renderer, detail, fine, probe};
use crate::gi::RadianceCache;
use crate::gi::entries::{IRRADIANCE_VARIATION, LIGHT_VARIATION, Variation, openness_varies};
use crate::gpu_scene::GpuScene;
use crate::light::groups::{Lights, luminance};
use crate::params::EstimatorKind;
use crate::passes::compose::ComposePass;
use crate::passes::filter::FilterPass;
use crate::passes::gbuffer::GBufferPass;
use crate::passes::interpolate::InterpolatePass;
use crate::passes::resolve::ResolvePass;
use crate::passes::sensor_maps::{EmitterFronts, StrategyDesc, TEXEL_BYTES};
use crate::scene::Scene;
use crate::scene::bvh::Bvh;
use crate::sensors::SensorKind;
use crate::sensors::hints;
use crate::sensors::layout::SensorLayout;
use crate::strategy::{self, Cache, Choice, StrategyKind, StrategyRequest};
use crate::supersample::ShadowPoints;
use crate::vk::Device;

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
    let config = RendererConfig::fixed(estimator, sensor, strategy::CHECK_RD, kind);
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
    let config = RendererConfig::fixed(estimator, sensor, rd, kind);
    let layout = config.layout(&Lights::new(&scene.mesh));
    let budget = config.batch_budget(device, &layout);
    let cull_triangles = config.cull_triangles();
    let desc = StrategyDesc { layout, fronts: fronts(estimator), rd, budget, cull_triangles };
    crate::passes::sensor_maps::unsupported(kind, device, &desc)
}

/// What emitter fronts leave in the maps with `estimator`.
pub(super) fn fronts(estimator: EstimatorKind) -> EmitterFronts {
    match estimator {
        EstimatorKind::Exact => EmitterFronts::Group,
        EstimatorKind::Paper => EmitterFronts::Emission,
    }
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
        let config = RendererConfig::new(EstimatorKind::default(), sensor, sensor_size);
        RendererBuilder { device, scene, config, cache: None, events: None }
    }

    pub(super) fn new(device: &Arc<Device>, scene: &Scene, config: RendererConfig, choice: Choice) -> Result<Self> {
        check_textures(device, &scene.mesh.textures)?;
        let scale = scene.mesh.scale();
        let hierarchy = cluster_hierarchy(device, scene, config.detail);
        let lights = Lights::new(&scene.mesh);
        let layout = config.layout(&lights);
        let estimate = Estimate::new(&config, &lights, scale);
        let (bias, near) = estimate.offsets;
        // The scene's triangles and points on its lights: the refinement's light hints, and where the radiance
        // cache's pieces are halved.
        let bvh = Bvh::of_mesh(&scene.mesh);
        let mut light_points = (estimate.groups > 0).then(|| hints::light_points(&lights));
        // A sky map's bright patches too: its shadows split quads as the lights' do (the shares, by group,
        // ignore these points).
        if let Some(sky) = &scene.sky {
            let points = light_points.get_or_insert_with(Vec::new);
            points.extend(hints::sky_points(sky, &scene.mesh.bounds, points.len()));
        }
        let shadow_points = (estimate.groups > 0).then(|| ShadowPoints::new(&lights));
        if let Some(c) = config.cache {
            check_cache_size(device, RadianceCache::bytes_at_least(&scene.mesh, c.resolution), c.resolution)?;
        }
        let cache = config.cache.map(|c| {
            let lod = hierarchy.as_ref().map(lod_triangles).unwrap_or_default();
            // The lights' irradiance in closed form where it is cheap (as for the exact interpolation).
            let few = estimate.few_emitters;
            let irradiance = |p: Vec3, n: Vec3| lights.unoccluded(p + n * bias, n).iter().map(|&e| luminance(e)).sum();
            let direct = |points: &[Vec3], n: Vec3| {
                let Some(hinted) = &light_points else { return false };
                let seen = points.iter().map(|&p| hints::mask(&bvh, hinted, (p, n), bias, near).count_ones());
                let (lo, hi) = seen.fold((u32::MAX, 0), |(lo, hi), s| (lo.min(s), hi.max(s)));
                (hi - lo) as f32 > LIGHT_VARIATION * hinted.len() as f32
                    || few && {
                        let e = points.iter().map(|&p| irradiance(p, n));
                        let (dim, bright) = e.fold((f32::MAX, 0.0f32), |(lo, hi), e: f32| (lo.min(e), hi.max(e)));
                        bright > IRRADIANCE_VARIATION * dim
                    }
            };
            let varies = |points: &[Vec3], normals: &[Vec3], n: Vec3| Variation {
                direct: [n, -n].into_iter().any(|n| direct(points, n)),
                openness: [1.0, -1.0].into_iter().any(|side| openness_varies(&bvh, (points, normals), side, bias)),
            };
            RadianceCache::build(&scene.mesh, c.resolution, &lod, Some(&varies), (bias, near))
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
                let desc = StrategyDesc {
                    layout,
                    fronts: EmitterFronts::Group,
                    rd: c.sensor_size,
                    budget: quarter,
                    cull_triangles: config.cull_triangles(),
                };
                let runner = BatchRunner::new(device, &gpu_scene, choice.strategy, desc, config.in_flight, offsets)?;
                Some((points, runner.with_rows()?))
            }
            _ => None,
        };
        let desc = StrategyDesc {
            layout,
            fronts: fronts(config.estimator),
            rd: config.sensor_size,
            budget,
            cull_triangles: config.cull_triangles(),
        };
        // The finer sensors where a slit falls between texels (`fine`): an eighth of the budget, if that holds
        // at least one of them. With the exact estimator only: the paper's is reproduced as it is.
        let fine = match fine::fine_rd(config.sensor_size).filter(|_| desc.exact()) {
            Some(rd) if budget / 8 >= layout.layers() as u64 * (rd as u64).pow(2) * TEXEL_BYTES => {
                let desc = StrategyDesc { rd, budget: budget / 8, ..desc };
                budget -= budget / 8;
                Some(BatchRunner::new(device, &gpu_scene, choice.strategy, desc, config.in_flight, offsets)?)
            }
            _ => None,
        };
        let desc = StrategyDesc { budget, ..desc };
        Ok(Self {
            host: scene.clone(),
            bvh,
            light_points,
            shadow_points,
            runner: {
                let runner = BatchRunner::new(device, &gpu_scene, choice.strategy, desc, config.in_flight, offsets)?;
                // The radiance cache's first bounce reads the transport's rows from the render's maps where
                // no shadow rays give its direct light (`gi::solve`).
                if cache.is_some() && !estimate.direct_by_rays { runner.with_rows()? } else { runner }
            },
            fine,
            passes: PostPasses {
                interpolate: InterpolatePass::new(device)?,
                filter: FilterPass::new(device)?,
                compose: ComposePass::new(device)?,
                resolve: ResolvePass::new(device)?,
            },
            gbuffer: GBufferPass::new(device, &gpu_scene)?,
            scene: gpu_scene,
            cache,
            estimate,
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
