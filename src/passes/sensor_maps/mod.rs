//! Sensor-map pass (paper §III-E, DESIGN.md §3 step 3): renders batches of sensors and hands their maps to
//! the reduction. How many sensors one submission draws, and how, is a [`Strategy`]; they all produce the
//! same sensor maps (checked by `crate::strategy` before use) and differ only in speed:
//!
//! | strategy     | per batch                                                   | limit per pass            |
//! |--------------|-------------------------------------------------------------|---------------------------|
//! | `per-sensor` | one render pass and one submission per sensor (paper's DX9) | 1 sensor                  |
//! | `single-cb`  | one render pass per sensor, all in one command buffer       | 1 sensor                  |
//! | `multiview`  | `VK_KHR_multiview`: view i of a pass draws into layer i     | `maxMultiviewViewCount`   |
//! | `layered`    | one instanced draw, `gl_Layer` from the vertex shader       | `maxFramebufferLayers`    |
//! | `atlas`      | one instanced draw into tiles of one 2D image (ours)        | `maxFramebufferWidth²`    |
//!
//! Shaders: `glsl/sensor_<strategy>.vert` (all include `sensor_common.glsl`) and `glsl/sensor.frag`.

mod atlas;
mod layered;
mod multiview;
mod per_sensor;

use std::fmt;
use std::sync::Arc;
use std::time::Duration;

use anyhow::{Result, bail, ensure};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;

use crate::gpu_scene::GpuScene;
use crate::gpu_types::{GpuSensorView, SensorPush, VERTEX_ATTRIBUTES, VERTEX_STRIDE};
use crate::passes::reduce::ReducePass;
use crate::passes::{DEPTH_COMPARE, DEPTH_FORMAT};
use crate::sensors::SensorKind;
use crate::sensors::frame::SensorFrame;
use crate::sensors::layout::ViewLayout;
use crate::shaders;
use crate::vk::image::ImageView;
use crate::vk::{
    Buffer, DescriptorPool, Device, Framebuffer, GraphicsDesc, Image, ImageDesc, Pipeline, PipelineLayout, RenderPass,
    SetWriter, barrier,
};

/// Texel format of the sensor maps: half floats hold `Ck` to 3 significant digits up to 65504, ample for
/// radiance, at half the bandwidth of RGBA32F (measured in docs/BENCHMARKS.md).
pub const MAP_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// Bytes per sensor-map texel: colour and depth.
pub const TEXEL_BYTES: u64 = 8 + 4;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StrategyKind {
    PerSensor,
    SingleCb,
    Multiview,
    #[default]
    Layered,
    Atlas,
}

impl StrategyKind {
    pub const ALL: [StrategyKind; 5] = [Self::PerSensor, Self::SingleCb, Self::Multiview, Self::Layered, Self::Atlas];

    pub fn name(self) -> &'static str {
        match self {
            Self::PerSensor => "per-sensor",
            Self::SingleCb => "single-cb",
            Self::Multiview => "multiview",
            Self::Layered => "layered",
            Self::Atlas => "atlas",
        }
    }

    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name).ok_or_else(|| {
            let names: Vec<_> = Self::ALL.iter().map(|k| k.name()).collect();
            anyhow::anyhow!("unknown strategy '{name}': expected auto or one of {}", names.join(", "))
        })
    }
}

impl fmt::Display for StrategyKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What a strategy needs besides its sensors.
pub struct SenseContext<'a> {
    pub device: &'a Arc<Device>,
    pub scene: &'a GpuScene,
    /// Bound to this strategy's maps and the radiance map; its pixel list holds the batch's sensors.
    pub reduce: &'a ReducePass,
    pub epsilon: f32,
    pub background: Vec3,
}

/// One way of rendering a batch of sensor maps.
pub trait Strategy {
    fn kind(&self) -> StrategyKind;
    /// Sensors per batch.
    fn capacity(&self) -> u32;
    /// The image holding the maps, and the atlas columns (0 when the maps are array layers).
    fn maps(&self) -> (&Image, u32);
    /// Renders the maps of `frames` (at most [`Strategy::capacity`]) and reduces them into the radiance
    /// map. Returns the time from submission to completion summed over its submissions.
    fn sense(&mut self, ctx: &SenseContext<'_>, frames: &[SensorFrame]) -> Result<Duration>;
}

/// Everything a strategy needs to know to size itself.
#[derive(Clone, Copy, Debug)]
pub struct StrategyDesc {
    pub sensor: SensorKind,
    pub rd: u32,
    /// Bytes for one batch's maps and depth.
    pub budget: u64,
    /// Near plane of the sensor views.
    pub near: f32,
}

impl StrategyDesc {
    pub fn layers(&self) -> u32 {
        self.sensor.layers()
    }

    /// Sensors the memory budget allows in one batch (at least one).
    pub fn sensors_in_budget(&self, device: &Device) -> Result<u32> {
        let per_sensor = self.layers() as u64 * (self.rd as u64).pow(2) * TEXEL_BYTES;
        ensure!(
            per_sensor <= device.adapter.limits.max_memory_allocation_size
                && per_sensor <= device.adapter.device_local_bytes,
            "one sensor of {}² texels needs {} MiB, more than this device can allocate",
            self.rd,
            per_sensor >> 20
        );
        Ok(((self.budget / per_sensor) as u32).max(1))
    }
}

/// Why a strategy cannot run on a device, if it cannot.
pub fn unsupported(kind: StrategyKind, device: &Device, desc: &StrategyDesc) -> Option<String> {
    let f = device.adapter.features;
    let l = &device.adapter.limits;
    if desc.sensor == SensorKind::Hemicube && !f.shader_clip_distance {
        return Some("no clip distances (hemicube half faces)".into());
    }
    match kind {
        StrategyKind::PerSensor | StrategyKind::SingleCb | StrategyKind::Layered if !f.shader_output_layer => {
            Some("no shaderOutputLayer (gl_Layer from the vertex shader)".into())
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
    })
}

/// The sensor maps and their depth buffer: `layers` layers of `width × height` (array strategies: rd × rd
/// per sensor layer; the atlas: one large layer).
struct MapImages {
    maps: Image,
    depth: Image,
}

impl MapImages {
    fn new(device: &Arc<Device>, width: u32, height: u32, layers: u32) -> Result<Self> {
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
        let maps = Image::new(device, "sensor maps", desc(MAP_FORMAT, color))?;
        let depth =
            Image::new(device, "sensor depth", desc(DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT))?;
        // The reduction binds every layer, and a smaller batch renders (and transitions) only the first
        // ones: all layers start out in GENERAL.
        device.submit_and_wait(|cmd| {
            barrier::discard_to_general(device, cmd, maps.raw, maps.full_range(), vk::PipelineStageFlags::TOP_OF_PIPE);
            Ok(())
        })?;
        Ok(Self { maps, depth })
    }

    /// A framebuffer over layers `first..first + count` of the maps and depth. `framebuffer_layers` is
    /// `count` for layered rendering, 1 for multiview (whose view mask addresses the layers).
    fn layer_framebuffer(
        &self,
        device: &Arc<Device>,
        render_pass: &RenderPass,
        (first, count): (u32, u32),
        framebuffer_layers: u32,
    ) -> Result<LayerFramebuffer> {
        let color = self.maps.layer_view(first, count)?;
        let depth = self.depth.layer_view(first, count)?;
        let extent = self.maps.extent();
        let framebuffer = Framebuffer::new(device, render_pass, &[color.raw, depth.raw], extent, framebuffer_layers)?;
        Ok(LayerFramebuffer { framebuffer, _color: color, _depth: depth })
    }

    fn clears(background: Vec3) -> [vk::ClearValue; 2] {
        [
            vk::ClearValue { color: vk::ClearColorValue { float32: background.extend(1.0).to_array() } },
            vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } },
        ]
    }
}

/// A framebuffer over some layers of [`MapImages`], owning the views it was made from.
struct LayerFramebuffer {
    // Field order is drop order: the framebuffer before the views it refers to.
    framebuffer: Framebuffer,
    _color: ImageView,
    _depth: ImageView,
}

/// A sensor pipeline: the render pass, the views buffer, and the pipeline drawing the scene into them.
struct SensorPipeline {
    // Field order is drop order.
    pipeline: Pipeline,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    layout: PipelineLayout,
    render_pass: RenderPass,
    views: Buffer,
}

impl SensorPipeline {
    /// `view_mask` 0 for ordinary passes; `max_views` entries in the views buffer.
    fn new(device: &Arc<Device>, scene: &GpuScene, vertex: &[u8], view_mask: u32, max_views: usize) -> Result<Self> {
        let render_pass = RenderPass::new(device, &[MAP_FORMAT], Some(DEPTH_FORMAT), view_mask)?;
        let views = Buffer::new(
            device,
            "sensor views",
            (max_views * size_of::<GpuSensorView>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let stage = vk::ShaderStageFlags::VERTEX;
        let layout = PipelineLayout::new(
            device,
            &[(0, storage, stage), (1, storage, stage)],
            size_of::<SensorPush>() as u32,
            stage,
        )?;
        let pool = DescriptorPool::new(device, 1, &[(storage, 2)])?;
        let set = pool.allocate(&layout)?;
        SetWriter::new(set).storage_buffer(0, &views).storage_buffer(1, &scene.surfaces).apply(device);
        let pipeline = Pipeline::graphics(
            device,
            &layout,
            &GraphicsDesc {
                vertex,
                fragment: shaders::SENSOR_FRAG,
                render_pass: render_pass.raw,
                color_attachments: 1,
                vertex_stride: VERTEX_STRIDE,
                vertex_attributes: &VERTEX_ATTRIBUTES,
                depth_compare: Some(DEPTH_COMPARE),
            },
        )?;
        Ok(Self { pipeline, _pool: pool, set, layout, render_pass, views })
    }

    /// Binds pipeline, descriptors and the scene's vertices.
    fn bind(&self, device: &Device, cmd: vk::CommandBuffer, scene: &GpuScene) {
        self.pipeline.bind(device, cmd, vk::PipelineBindPoint::GRAPHICS, &self.layout, self.set);
        scene.bind_vertices(device, cmd);
    }

    /// Draws the scene `instances` times starting at view `first_instance`.
    fn draw(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        scene: &GpuScene,
        push: &SensorPush,
        instances: u32,
        first_instance: u32,
    ) {
        self.layout.push(cmd, push);
        // SAFETY: recording state inside a render pass of this pipeline's render pass.
        unsafe { device.raw.cmd_draw(cmd, scene.vertex_count, instances, 0, first_instance) };
    }
}

impl SensorPipeline {
    /// Writes the views of `frames`, sensor-major, in [`crate::sensors::layout::views`] order; `slot(i, view)`
    /// gives each view's `layer` field (the layer or tile it draws into).
    fn write_views(
        &mut self,
        frames: &[SensorFrame],
        layouts: &[ViewLayout],
        near: f32,
        slot: impl Fn(u32, &ViewLayout) -> u32,
    ) -> Result<()> {
        let views: Vec<GpuSensorView> = frames
            .iter()
            .enumerate()
            .flat_map(|(i, frame)| {
                let slot = &slot;
                layouts.iter().map(move |v| {
                    GpuSensorView::new(
                        frame.view_proj(v, near),
                        v.clip_horizon.then(|| frame.horizon()),
                        slot(i as u32, v),
                    )
                })
            })
            .collect();
        self.views.write(0, &views)
    }
}
