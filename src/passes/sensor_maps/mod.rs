//! Sensor-map pass (paper §III-E, docs/DESIGN.md §3 step 3): records batches of sensors' maps for the
//! reduction. How one batch is drawn is a [`Strategy`]; they all produce the same sensor maps (checked by
//! `crate::strategy` before use) and differ only in speed:
//!
//! | strategy     | per batch                                                   | limit per pass            |
//! |--------------|-------------------------------------------------------------|---------------------------|
//! | `per-sensor` | one render pass and one submission per sensor (paper's DX9) | 1 sensor                  |
//! | `single-cb`  | one render pass per sensor, all in one command buffer       | 1 sensor                  |
//! | `multiview`  | `VK_KHR_multiview`: view i of a pass draws into layer i     | `maxMultiviewViewCount`   |
//! | `layered`    | one instanced draw, `gl_Layer` from the vertex shader       | `maxFramebufferLayers`    |
//! | `atlas`      | one instanced draw into tiles of one 2D image (ours)        | `maxFramebufferWidth²`    |
//! | `compute`    | a compute shader rasterizes, a workgroup per layer (ours)   | `maxImageArrayLayers`     |
//!
//! A strategy only *records*: the renderer's batch runner owns the batches in flight, each with its own
//! [`SlotMaps`] (made by [`Strategy::new_slot`]), and submits them.
//!
//! When the scene has a cluster hierarchy (`GpuScene::clusters`), every strategy but `multiview` draws
//! each view from its own list of indexed indirect draws ([`DrawLists`]), which the culling pass
//! (`passes::cull`) fills before the maps are drawn; else each view draws the whole triangle soup.
//! Shaders: `glsl/sensor_<strategy>.vert` (all include `sensor_common.glsl`) and `glsl/sensor.frag`;
//! `glsl/sensor_compute.comp`; all shade a texel with `glsl/sensor_shade.glsl`.

mod atlas;
mod compute;
mod draw;
mod layered;
mod multiview;
mod per_sensor;

pub use draw::{DrawBytes, DrawLists};
use draw::{SensorInputs, SensorPipeline};

use std::sync::Arc;

use anyhow::{Result, bail, ensure};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;

use crate::gpu_scene::{GpuScene, TreeShape};
use crate::gpu_types::{GpuDrawCommand, GpuSensorView, SensorPush, VERTEX_ATTRIBUTES, VERTEX_STRIDE};
use crate::passes::{DEPTH_COMPARE, DEPTH_FORMAT};
use crate::sensors::layout::SensorLayout;
use crate::sensors::views::BatchViews;
use crate::shaders;
use crate::strategy::StrategyKind;
use crate::vk::{
    Access, Buffer, DescriptorPool, Device, Encoder, Framebuffer, GraphicsDesc, Image, ImageDesc, ImageView, Pipeline,
    PipelineLayout, RenderPass, RenderPassScope, SetWriter, barrier,
};

/// Texel format of the sensor maps: half floats hold `Ck` to 3 significant digits up to 65504, ample for
/// radiance, at half the bandwidth of RGBA32F (measured in docs/BENCHMARKS.md).
pub const MAP_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// Bytes per sensor-map texel: colour and depth.
pub const TEXEL_BYTES: u64 = 8 + 4;
/// The largest finite half float.
const MAP_MAX: f32 = 65504.0;

/// What the paper's estimator divides `Ke` by in the maps (and the reduction multiplies back, on texels
/// whose alpha marks an emitter's front): the smallest power of two that keeps the brightest emitter within
/// [`MAP_FORMAT`]'s range. A power of two changes only the exponent, so nothing is lost (1 for every
/// emitter up to 65504, so those maps are as before); the exact estimator writes no `Ke` into the maps.
pub fn emission_scale(scene: &GpuScene, fronts: EmitterFronts) -> f32 {
    let brightest = scene.lights.emitters.iter().map(|e| e.ke.max_element()).fold(0.0, f32::max);
    let mut scale = 1.0f32;
    while fronts == EmitterFronts::Emission && brightest / scale > MAP_MAX {
        scale *= 2.0;
    }
    scale
}

/// Where a batch's maps lie in their image, for the reduction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapLayout {
    /// Layer `sensor × layers + layer` of a 2D array.
    Layers,
    /// Tile `sensor × layers + layer` of one 2D image, `columns` tiles per row.
    Atlas { columns: u32 },
}

/// What `Ck` is made of besides the scene (paper eq. 1–2): ε for non-emitters, the background where a view
/// sees nothing, and with global illumination the radiance cache's reflected light on every surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CkParams {
    pub epsilon: f32,
    pub background: Background,
    /// What surfaces return of the radiance cache (`GpuScene::cache`).
    pub cache: CacheRead,
}

/// What a sensor texel holds of the radiance cache (docs/DESIGN.md §10; `glsl/sensor_shade.glsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CacheRead {
    /// Nothing: `Kd·ε` only.
    #[default]
    Off,
    /// The reflected light of the cache's value at the point the texel sees, as the values are now.
    Values,
    /// Which of the cache's values that is, instead of any light in the main layers (emitter fronts keep
    /// their group, so the zoom views measure the lights as ever): the transport's rows
    /// (`gi::transport`, read by `passes::transport`). Only with ε 0 and a black background, whose main
    /// layers would sum to nothing.
    Entries,
}

impl CacheRead {
    /// `SensorPush::cache`: `glsl/types.glsl`'s `CACHE_*`.
    fn code(self) -> u32 {
        match self {
            Self::Off => 0,
            Self::Values => 1,
            Self::Entries => 2,
        }
    }
}

/// What a sensor texel that sees no geometry holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Background {
    /// This radiance: the constant sky (black for the passes that must not see the sky).
    Constant(Vec3),
    /// The scene's sky map along the texel's direction: the maps mark such texels with alpha −1 and the
    /// reduction looks the map up (`glsl/reduce.comp`).
    SkyMap,
}

impl Background {
    pub const BLACK: Self = Self::Constant(Vec3::ZERO);

    pub fn is_black(&self) -> bool {
        *self == Self::BLACK
    }

    /// The maps' clear colour: the radiance and alpha 0 (no emitter's group), or the sky map's mark.
    pub(crate) fn clear_colour(&self) -> [f32; 4] {
        match self {
            Self::Constant(radiance) => radiance.extend(0.0).to_array(),
            Self::SkyMap => [0.0, 0.0, 0.0, -1.0],
        }
    }
}

impl CkParams {
    /// The paper's `Kd·ε` and `background`, no cache.
    pub fn epsilon(epsilon: f32, background: Background) -> Self {
        Self { epsilon, background, cache: CacheRead::Off }
    }

    /// The sensor push of these (the rest for the strategy and pipeline to fill in).
    fn push(&self) -> SensorPush {
        SensorPush { epsilon: self.epsilon, cache: self.cache.code(), ..Default::default() }
    }
}

/// One way of recording a batch of sensor maps.
pub trait Strategy {
    fn kind(&self) -> StrategyKind;
    /// Sensors per batch.
    fn capacity(&self) -> u32;
    fn map_layout(&self) -> MapLayout;
    /// The resources of one batch in flight: its maps and what draws into them.
    fn new_slot(&self) -> Result<SlotMaps>;
    /// Writes the views of `batch` (at most [`Strategy::capacity`] sensors) into `slot`, each placed in its
    /// layer or tile, and records their maps. The slot's previous batch has completed (the runner waited).
    fn record(&self, enc: &Encoder<'_>, slot: &mut SlotMaps, batch: &BatchViews, ck: CkParams) -> Result<()>;
}

/// What the front of an emitter leaves in the sensor maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmitterFronts {
    /// Its `Ke` (the paper's estimator sums it with the rest).
    Emission,
    /// 0 and its light group (the exact estimator: the emitters' light is computed in closed form, and with
    /// light groups their visibility measured in zoom views; without, as the radiance cache's later bounces
    /// sense, it is not measured at all).
    Group,
}

/// Everything a strategy needs to know to size itself.
#[derive(Clone, Copy, Debug)]
pub struct StrategyDesc {
    /// The layers of one sensor: its main layers and a zoom pair per light group measured.
    pub layout: SensorLayout,
    pub fronts: EmitterFronts,
    pub rd: u32,
    /// Bytes for one batch's maps and depth.
    pub budget: u64,
    /// Drawn from clusters: drop the triangles that cover no texel first (`passes::cull_triangles`).
    pub cull_triangles: bool,
}

impl StrategyDesc {
    pub fn layers(&self) -> u32 {
        self.layout.layers()
    }

    /// Whether emitter fronts leave 0 and their group in the maps (the exact estimator).
    pub fn exact(&self) -> bool {
        self.fronts == EmitterFronts::Group
    }

    /// Sensors one batch may hold: what the memory budget allows (maps, depth and what draws them from
    /// clusters, per sensor), what one storage buffer of draw lists may hold, and what one reduction
    /// dispatch can cover (at least one).
    pub fn batch_limit(&self, device: &Device, draw: DrawBytes) -> Result<u32> {
        let maps = self.layers() as u64 * (self.rd as u64).pow(2) * TEXEL_BYTES;
        let per_sensor = maps + draw.memory;
        let draw_bytes = draw.lists.max(draw.pool);
        let limits = &device.adapter.limits;
        ensure!(
            per_sensor <= limits.max_memory_allocation_size && per_sensor <= device.adapter.device_local_bytes,
            "one sensor's maps ({per_sensor} bytes at rd {}) exceed this device's memory",
            self.rd
        );
        let by_budget = (self.budget / per_sensor).max(1);
        let by_range = (limits.max_storage_buffer_range as u64).checked_div(draw_bytes).unwrap_or(u64::MAX);
        ensure!(by_range >= 1, "one sensor's draw lists ({draw_bytes} bytes) exceed a storage buffer");
        Ok(by_budget.min(by_range).min(limits.max_compute_work_group_count[0] as u64) as u32)
    }
}

/// Why `kind` cannot run on `device` for sensors described by `desc`, if it cannot.
pub fn unsupported(kind: StrategyKind, device: &Device, desc: &StrategyDesc) -> Option<String> {
    let (l, f) = (&device.adapter.limits, &device.adapter.features);
    if kind == StrategyKind::Compute {
        return (l.max_compute_shared_memory_size < compute::SHARED_BYTES).then(|| {
            format!("maxComputeSharedMemorySize {} < {} bytes", l.max_compute_shared_memory_size, compute::SHARED_BYTES)
        });
    }
    if !f.shader_clip_distance {
        return Some("no clip distances (hemicube side faces and zoom views need them)".into());
    }
    match kind {
        StrategyKind::Layered | StrategyKind::PerSensor | StrategyKind::SingleCb if !f.shader_output_layer => {
            Some("no shaderOutputLayer (gl_Layer from the vertex shader)".into())
        }
        StrategyKind::Layered | StrategyKind::PerSensor | StrategyKind::SingleCb
            if l.max_framebuffer_layers < desc.layers() =>
        {
            Some(format!("maxFramebufferLayers {} < {} layers per sensor", l.max_framebuffer_layers, desc.layers()))
        }
        StrategyKind::Multiview if !f.multiview => Some("no multiview".into()),
        StrategyKind::Multiview if l.max_multiview_view_count < desc.layers() => {
            Some(format!("maxMultiviewViewCount {} < {} layers per sensor", l.max_multiview_view_count, desc.layers()))
        }
        StrategyKind::Atlas if l.max_framebuffer_width.min(l.max_framebuffer_height) < desc.rd => {
            Some("sensor maps larger than a framebuffer".into())
        }
        _ => None,
    }
}

/// Why the sensor maps cannot draw from a cluster hierarchy whose views draw up to `max_per_view` clusters
/// on `device`, if they cannot: indirect draws must name their view (`firstInstance`) and be many.
pub fn culling_unsupported(device: &Device, max_per_view: u32) -> Option<String> {
    let f = &device.adapter.features;
    if !f.draw_indirect_first_instance {
        return Some("no drawIndirectFirstInstance".into());
    }
    if !f.multi_draw_indirect {
        return Some("no multiDrawIndirect".into());
    }
    let limit = device.adapter.limits.max_draw_indirect_count;
    (limit < max_per_view).then(|| format!("maxDrawIndirectCount {limit} < {max_per_view} clusters per view"))
}

/// Creates strategy `kind` for sensors described by `desc`.
pub fn create(
    kind: StrategyKind,
    device: &Arc<Device>,
    scene: &GpuScene,
    desc: StrategyDesc,
) -> Result<Box<dyn Strategy>> {
    if let Some(why) = unsupported(kind, device, &desc) {
        bail!("strategy {kind} cannot run on {}: {why}", device.adapter);
    }
    Ok(match kind {
        StrategyKind::PerSensor => Box::new(per_sensor::PerSensor::new(device, scene, desc, false)?),
        StrategyKind::SingleCb => Box::new(per_sensor::PerSensor::new(device, scene, desc, true)?),
        StrategyKind::Multiview => Box::new(multiview::Multiview::new(device, scene, desc)?),
        StrategyKind::Layered => Box::new(layered::Layered::new(device, scene, desc)?),
        StrategyKind::Atlas => Box::new(atlas::Atlas::new(device, scene, desc)?),
        StrategyKind::Compute => Box::new(compute::Compute::new(device, scene, desc)?),
    })
}

/// One batch's sensor maps and what draws into them. The meaning of `framebuffers` is the strategy's own
/// (one per sensor, per multiview group, or one for the whole batch).
pub struct SlotMaps {
    /// The maps the reduction reads: `width × height`, `layers` layers (array strategies: rd × rd per
    /// sensor layer; the atlas: one large layer).
    pub maps: Arc<Image>,
    depth: Arc<Image>,
    framebuffers: Vec<Framebuffer>,
    /// Layered: a framebuffer over the first layers, for a smaller batch (unused layers are not cleared).
    partial: Option<(u32, Framebuffer)>,
    /// The batch's views, host-written before recording.
    views: Buffer,
    /// Culled: each view's draws, filled by the culling pass.
    draws: Option<DrawLists>,
    // Dropped after the set it holds (never used by the GPU after the slot is dropped: the runner waits).
    set: vk::DescriptorSet,
    _pool: DescriptorPool,
}

impl SlotMaps {
    /// Maps and depth of `width × height × layers`, all layers in `GENERAL` (the reduction binds every
    /// layer, and a smaller batch renders, and so transitions, only the first ones).
    fn new(pipeline: &SensorPipeline, size: (u32, u32, u32), max_views: usize) -> Result<Self> {
        let device = &pipeline.inputs.device;
        let pool = DescriptorPool::new(device, 1, &[(vk::DescriptorType::STORAGE_BUFFER, 8)])?;
        let set = pool.allocate(&pipeline.layout)?;
        let slot = Self::with_set(&pipeline.inputs, size, max_views, (set, pool))?;
        slot.input_writer(&pipeline.inputs).apply(device);
        Ok(slot)
    }

    /// The maps, their views buffer and draw lists for `inputs`, with descriptor set `set` (from `pool`) that
    /// the caller writes.
    fn with_set(
        inputs: &SensorInputs,
        (width, height, layers): (u32, u32, u32),
        max_views: usize,
        (set, pool): (vk::DescriptorSet, DescriptorPool),
    ) -> Result<Self> {
        let device = &inputs.device;
        let desc = |format, usage| ImageDesc {
            format,
            width,
            height,
            layers,
            usage,
            view_type: vk::ImageViewType::TYPE_2D_ARRAY,
        };
        let color =
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let maps = Arc::new(Image::new(device, "sensor maps", desc(MAP_FORMAT, color))?);
        let depth = Arc::new(Image::new(
            device,
            "sensor depth",
            desc(DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )?);
        device.submit_and_wait(|enc| {
            let (before, after) =
                ((&[Access::Nothing][..], vk::ImageLayout::UNDEFINED), (&[Access::Any][..], vk::ImageLayout::GENERAL));
            barrier::image(enc, &maps, maps.full_range(), before, after);
            Ok(())
        })?;
        let views = Buffer::new(
            device,
            "sensor views",
            (max_views * size_of::<GpuSensorView>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        let draws = inputs.culled.as_ref().map(|c| DrawLists::new(device, max_views as u32, c)).transpose()?;
        Ok(Self { maps, depth, framebuffers: Vec::new(), partial: None, views, draws, set, _pool: pool })
    }

    /// The writes of bindings 0–7 of the slot's set, what every sensor shader reads: the views, materials,
    /// radiance cache, texture coordinates and textures.
    fn input_writer(&self, inputs: &SensorInputs) -> SetWriter {
        // Texture coordinates of the vertices drawn: the clusters' where the maps are drawn from them.
        let uvs = inputs.culled.as_ref().map_or(&inputs.uvs, |c| &c.uvs);
        SetWriter::new(self.set)
            .storage_buffer(0, &self.views)
            .storage_buffer(1, &inputs.surfaces)
            .storage_buffer(2, &inputs.cache[0])
            .storage_buffer(3, &inputs.cache[1])
            .storage_buffer(4, &inputs.cache[2])
            .storage_buffer(5, uvs)
            .storage_buffer(6, &inputs.textures[0])
            .storage_buffer(7, &inputs.textures[1])
    }

    /// The views of the batch being recorded, sensor-major (`BatchViews` order), for the culling pass.
    pub fn views(&self) -> &Buffer {
        &self.views
    }

    /// The draw lists the culling pass must fill before the maps are drawn; `None`: full detail.
    pub fn draws(&self) -> Option<&DrawLists> {
        self.draws.as_ref()
    }

    /// A framebuffer over layers `first..first + count` of the maps and depth. `framebuffer_layers` is
    /// `count` for layered rendering, 1 for multiview (whose view mask addresses the layers).
    fn layer_framebuffer(
        &self,
        pipeline: &SensorPipeline,
        (first, count): (u32, u32),
        framebuffer_layers: u32,
    ) -> Result<Framebuffer> {
        let attachments =
            vec![ImageView::layers(&self.maps, first, count)?, ImageView::layers(&self.depth, first, count)?];
        Framebuffer::new(&pipeline.inputs.device, &pipeline.render_pass, attachments, framebuffer_layers)
    }

    /// A layered framebuffer over every layer.
    fn whole_framebuffer(&self, pipeline: &SensorPipeline) -> Result<Framebuffer> {
        let layers = self.maps.desc.layers;
        self.layer_framebuffer(pipeline, (0, layers), layers)
    }

    /// What a texel that sees no geometry holds (see `glsl/sensor.frag`), and the far depth.
    fn clears(background: Background) -> [vk::ClearValue; 2] {
        [
            vk::ClearValue { color: vk::ClearColorValue { float32: background.clear_colour() } },
            vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } },
        ]
    }

    /// Writes the views of `batch`, sensor-major, each in the layer or tile `place(sensor, layer within the
    /// sensor)`.
    fn write_views(&mut self, batch: &BatchViews, place: impl Fn(u32, u32) -> u32) -> Result<()> {
        let place = &place;
        let views: Vec<GpuSensorView> = (0..batch.len())
            .flat_map(|i| batch.of(i).iter().map(move |v| GpuSensorView { layer: place(i as u32, v.layer), ..*v }))
            .collect();
        self.views.write(0, &views)
    }
}
