//! One render, end to end (DESIGN.md §3): G-buffer → sensors on the grid → rounds of refinement, each
//! sensing a batch list on the GPU (sensor maps + reduction) → interpolation → id-constrained filter →
//! composition. The CPU only decides where sensors go; every image operation runs on the GPU.

use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use ash::vk;
use glam::{Vec3, Vec4};
use gpu_allocator::MemoryLocation;
use serde::Serialize;

use crate::gbuffer::GBufferData;
use crate::gpu_scene::GpuScene;
use crate::params::{EstimatorParams, RenderParams};
use crate::passes::compose::ComposePass;
use crate::passes::filter::FilterPass;
use crate::passes::gbuffer::{self, GBuffer, GBufferPass};
use crate::passes::interpolate::InterpolatePass;
use crate::passes::reduce::ReducePass;
use crate::passes::sensor_maps::{self, SenseContext, Strategy, StrategyDesc, StrategyKind};
use crate::scene::{ImageSize, Scene};
use crate::sensors::SensorKind;
use crate::sensors::frame::{self, SensorFrame};
use crate::sensors::refine::Refinement;
use crate::vk::{Buffer, Device, barrier, transfer};

/// Progress callbacks for long renders.
pub trait Progress {
    /// `n` more sensors will be rendered.
    fn queued(&self, _n: u64) {}
    /// `n` more sensors are done.
    fn done(&self, _n: u64) {}
}

/// No progress reporting.
pub struct Quiet;
impl Progress for Quiet {}

/// The GPU state for rendering one scene with one kind and size of sensor, reusable across renders.
pub struct Renderer {
    // Field order is drop order; all of these hold the device.
    /// The images and buffers of the last render: the passes' descriptors refer to them, so they live
    /// until the next render replaces them.
    targets: Option<Targets>,
    strategy: Box<dyn Strategy>,
    reduce: ReducePass,
    interpolate: InterpolatePass,
    filter: FilterPass,
    compose: ComposePass,
    gbuffer: GBufferPass,
    scene: GpuScene,
    device: Arc<Device>,
    kind: SensorKind,
    rd: u32,
    scale: f32,
}

/// What a render measured, as printed and as written by `--stats-json`.
#[derive(Clone, Debug, Default, Serialize)]
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
    pub epsilon: f32,
    pub filter_radius: u32,
    /// Sensors rendered, in total and per refinement round.
    pub sensors: u64,
    pub sensors_per_round: Vec<u64>,
    pub interpolated_quads: u64,
    pub batch_size: u32,
    pub batches: u64,
    /// Wall time of the whole render.
    pub total_seconds: f64,
    /// Time from submission to completion of the sensor batches (sensor maps + reduction).
    pub gpu_sensor_seconds: f64,
    /// Time from submission to completion of the other GPU work (G-buffer, post-passes, read-backs).
    pub gpu_other_seconds: f64,
    /// The rest: placing sensors, building views, refinement decisions, waiting on nothing.
    pub host_seconds: f64,
    /// The paper's metric: total time / sensors, in milliseconds.
    pub sensor_time_ms: f64,
}

pub struct RenderOutput {
    pub size: ImageSize,
    /// `Le + albedo·R`.
    pub image: Vec<Vec4>,
    /// R after interpolation and filtering; w says how it was obtained (see `gpu_types::radiance_state`).
    pub radiance: Vec<Vec4>,
    pub gbuffer: GBufferData,
    pub stats: RenderStats,
}

/// Budget for one batch's sensor maps when none is given: an eighth of the device's largest local heap.
pub fn default_memory_budget(device: &Device) -> u64 {
    device.adapter.device_local_bytes / 8
}

impl Renderer {
    /// Sensors of `kind` and size `rd`, drawn by `strategy`; `memory_budget`: bytes for one batch's sensor
    /// maps and depth (default [`default_memory_budget`]).
    pub fn new(
        device: &Arc<Device>,
        scene: &Scene,
        kind: SensorKind,
        rd: u32,
        memory_budget: Option<u64>,
        strategy: StrategyKind,
    ) -> Result<Self> {
        let limits = &device.adapter.limits;
        kind.check_size(rd, limits.max_image_dimension_2d.min(limits.max_framebuffer_width))?;
        let scale = scene.mesh.scale();
        let gpu_scene = GpuScene::upload(device, scene)?;
        let budget = memory_budget.unwrap_or_else(|| default_memory_budget(device));
        let desc = StrategyDesc { sensor: kind, rd, budget, near: frame::NEAR * scale };
        let strategy = sensor_maps::create(strategy, device, &gpu_scene, desc)?;
        Ok(Self {
            targets: None,
            reduce: ReducePass::new(device, kind, rd, strategy.capacity())?,
            interpolate: InterpolatePass::new(device)?,
            filter: FilterPass::new(device)?,
            compose: ComposePass::new(device)?,
            gbuffer: GBufferPass::new(device, &gpu_scene)?,
            strategy,
            scene: gpu_scene,
            device: device.clone(),
            kind,
            rd,
            scale,
        })
    }

    pub fn batch_size(&self) -> u32 {
        self.strategy.capacity()
    }

    pub fn strategy(&self) -> StrategyKind {
        self.strategy.kind()
    }

    /// Renders the G-buffer of `scene` at `size`, makes this render's [`Targets`] (kept in `self.targets`)
    /// and binds the zeroed radiance map to the reduction. Returns the G-buffer's host copy.
    fn prepare(&mut self, scene: &Scene, size: ImageSize) -> Result<GBufferData> {
        let device = self.device.clone();
        let gpu_gbuffer = self.gbuffer.render(&device, &self.scene, &scene.camera, size, gbuffer::NEAR * self.scale)?;
        let g = gpu_gbuffer.read_back(&device)?;
        let targets = Targets {
            radiance: map_buffer(&device, "radiance map", size)?,
            filtered: map_buffer(&device, "filtered radiance map", size)?,
            image: map_buffer(&device, "final image", size)?,
            gbuffer: gpu_gbuffer,
        };
        let radiance = &targets.radiance;
        device.submit_and_wait(|cmd| {
            // SAFETY: recording state; the buffer outlives the wait.
            unsafe { device.raw.cmd_fill_buffer(cmd, radiance.raw, 0, vk::WHOLE_SIZE, 0) };
            Ok(())
        })?;
        let (maps, atlas_columns) = self.strategy.maps();
        self.reduce.bind(&device, maps, atlas_columns, radiance);
        self.targets = Some(targets);
        Ok(g)
    }

    fn targets(&self) -> &Targets {
        self.targets.as_ref().expect("prepare() ran")
    }

    /// R at `pixels` of `scene` seen at `size` (surface pixels only), and the host time sensing took (views,
    /// submissions, waits): for the strategy self-check, strategy selection and benchmarks.
    pub fn radiance_at(
        &mut self,
        scene: &Scene,
        size: ImageSize,
        pixels: &[u32],
        estimator: &EstimatorParams,
    ) -> Result<(Vec<Vec4>, Duration)> {
        let g = self.prepare(scene, size)?;
        let start = Instant::now();
        self.sense(&g, pixels, estimator.epsilon, estimator.background, &Quiet)?;
        let time = start.elapsed();
        let r =
            transfer::read_buffer::<Vec4>(&self.device, &self.targets().radiance, (size.width * size.height) as usize)?;
        Ok((pixels.iter().map(|&i| r[i as usize]).collect(), time))
    }

    /// Runs the reduction alone over the last batch's first `count` sensors again (their maps are still in
    /// place after [`Renderer::radiance_at`]); returns the time from submission to completion.
    pub fn reduction_only(&self, count: u32) -> Result<Duration> {
        let count = count.min(self.strategy.capacity());
        self.device.submit_and_wait(|cmd| {
            self.reduce.record(&self.device, cmd, 0, count);
            Ok(())
        })
    }

    /// Renders `scene` (the one this renderer was made for) at `size`.
    pub fn render(
        &mut self,
        scene: &Scene,
        size: ImageSize,
        params: &RenderParams,
        progress: &dyn Progress,
    ) -> Result<RenderOutput> {
        let start = Instant::now();
        let device = self.device.clone();
        let mut gpu_other = Duration::ZERO;
        let e = &params.estimator;

        let t = Instant::now();
        let g = self.prepare(scene, size)?;
        let pixels = size.width as u64 * size.height as u64;
        gpu_other += t.elapsed();

        // Sensors on the grid, then rounds of refinement until no quad asks for more (paper §III-G).
        let (mut refinement, mut pending) = Refinement::start(&g, params.tile, params.dradiance);
        let mut r: Vec<Vec4> = Vec::new();
        let mut sensor_time = Duration::ZERO;
        let (mut sensors, mut batches, mut per_round) = (0u64, 0u64, Vec::new());
        loop {
            if !pending.is_empty() {
                progress.queued(pending.len() as u64);
                let (time, n) = self.sense(&g, &pending, e.epsilon, e.background, progress)?;
                sensor_time += time;
                batches += n;
                sensors += pending.len() as u64;
                per_round.push(pending.len() as u64);
                let t = Instant::now();
                r = transfer::read_buffer::<Vec4>(&device, &self.targets().radiance, pixels as usize)?;
                gpu_other += t.elapsed();
            }
            if refinement.is_finished() {
                break;
            }
            pending = refinement.step(&r);
        }

        // Interpolation, filter, composition: one submission.
        let t = Instant::now();
        let targets = self.targets.as_ref().expect("prepare() ran");
        self.interpolate.bind(&device, refinement.interpolated(), &targets.radiance)?;
        self.filter.bind(&device, &targets.radiance, &targets.filtered, &targets.gbuffer.surface);
        self.compose.bind(&device, &targets.filtered, &targets.image, &targets.gbuffer);
        device.submit_and_wait(|cmd| {
            barrier::compute_to_compute(&device, cmd);
            self.interpolate.record(&device, cmd, size);
            barrier::compute_to_compute(&device, cmd);
            self.filter.record(&device, cmd, size, params.filter_radius);
            barrier::compute_to_compute(&device, cmd);
            self.compose.record(&device, cmd, size);
            Ok(())
        })?;
        let image = transfer::read_buffer::<Vec4>(&device, &targets.image, pixels as usize)?;
        let radiance = transfer::read_buffer::<Vec4>(&device, &targets.filtered, pixels as usize)?;
        gpu_other += t.elapsed();

        let total = start.elapsed();
        let stats = RenderStats {
            device: device.adapter.name.clone(),
            driver: device.adapter.driver.clone(),
            sensor: self.kind.to_string(),
            strategy: self.strategy.kind(),
            sensor_size: self.rd,
            width: size.width,
            height: size.height,
            tile: params.tile,
            dradiance: params.dradiance,
            epsilon: e.epsilon,
            filter_radius: params.filter_radius,
            sensors,
            sensors_per_round: per_round,
            interpolated_quads: refinement.interpolated().len() as u64,
            batch_size: self.strategy.capacity(),
            batches,
            total_seconds: total.as_secs_f64(),
            gpu_sensor_seconds: sensor_time.as_secs_f64(),
            gpu_other_seconds: gpu_other.as_secs_f64(),
            host_seconds: (total.saturating_sub(sensor_time + gpu_other)).as_secs_f64(),
            sensor_time_ms: if sensors > 0 { 1e3 * total.as_secs_f64() / sensors as f64 } else { 0.0 },
        };
        Ok(RenderOutput { size, image, radiance, gbuffer: g, stats })
    }

    /// Renders and reduces sensors at `pixels` (indices into the G-buffer `g`) into the bound radiance map.
    /// Returns the time the GPU batches took (submission to completion) and the number of batches.
    fn sense(
        &mut self,
        g: &GBufferData,
        pixels: &[u32],
        epsilon: f32,
        background: Vec3,
        progress: &dyn Progress,
    ) -> Result<(Duration, u64)> {
        let bias = frame::BIAS * self.scale;
        let mut time = Duration::ZERO;
        let mut batches = 0;
        for chunk in pixels.chunks(self.strategy.capacity() as usize) {
            let frames: Vec<SensorFrame> = chunk
                .iter()
                .map(|&i| SensorFrame::new(g.position[i as usize].truncate(), g.normal[i as usize].truncate(), bias))
                .collect();
            self.reduce.set_pixels(chunk)?;
            let ctx =
                SenseContext { device: &self.device, scene: &self.scene, reduce: &self.reduce, epsilon, background };
            time += self.strategy.sense(&ctx, &frames)?;
            batches += 1;
            progress.done(chunk.len() as u64);
        }
        Ok((time, batches))
    }
}

/// What one render writes on the GPU.
struct Targets {
    radiance: Buffer,
    filtered: Buffer,
    image: Buffer,
    gbuffer: GBuffer,
}

/// A radiance-map-sized buffer of `vec4` per pixel, written by compute passes and read back.
fn map_buffer(device: &Arc<Device>, name: &str, size: ImageSize) -> Result<Buffer> {
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    Buffer::new(device, name, size.width as u64 * size.height as u64 * 16, usage, MemoryLocation::GpuOnly)
}
