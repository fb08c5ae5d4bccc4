//! Sensor-map pass (paper §III-E, DESIGN.md §3 step 3): renders a batch of sensors into one 2D-array image,
//! `layers` consecutive layers per sensor (see `sensors::layout`), in one render pass and one instanced draw:
//! instance = one view of one sensor, `gl_Layer` = that view's layer. Shaders: `glsl/sensor_layered.vert`,
//! `glsl/sensor.frag`.
//!
//! ```text
//!   maps (2D array, rd × rd per layer):  | s0 L0 | s0 L1 | s0 L2 | s1 L0 | s1 L1 | … |   (hemicube: 3 per sensor)
//! ```

use std::sync::Arc;

use anyhow::{Result, ensure};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;

use crate::gpu_scene::GpuScene;
use crate::gpu_types::{GpuSensorView, SensorPush, VERTEX_POSITION_OFFSET, VERTEX_SURFACE_OFFSET, Vertex};
use crate::sensors::SensorKind;
use crate::sensors::frame::SensorFrame;
use crate::sensors::layout::{ViewLayout, views};
use crate::shaders;
use crate::vk::image::ImageView;
use crate::vk::{
    Buffer, DescriptorPool, Device, Framebuffer, GraphicsDesc, Image, ImageDesc, Pipeline, PipelineLayout, RenderPass,
    SetWriter, barrier,
};

/// Texel format of the sensor maps: half floats hold `Ck` to 3 significant digits up to 65504, ample for
/// radiance, at half the bandwidth of RGBA32F (measured in docs/BENCHMARKS.md).
pub const MAP_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
pub const MAP_TEXEL_BYTES: u64 = 8;
const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
const DEPTH_TEXEL_BYTES: u64 = 4;

/// Sensors per batch: as many as the device's layer limits and the memory budget allow.
pub fn batch_size(device: &Device, kind: SensorKind, rd: u32, budget_bytes: u64) -> Result<u32> {
    let limits = &device.adapter.limits;
    let layers = kind.layers();
    let by_layers = limits.max_framebuffer_layers.min(limits.max_image_array_layers) / layers;
    let per_sensor = layers as u64 * (rd as u64).pow(2) * (MAP_TEXEL_BYTES + DEPTH_TEXEL_BYTES);
    ensure!(
        per_sensor <= limits.max_memory_allocation_size && per_sensor <= device.adapter.device_local_bytes,
        "one sensor of {rd}² texels needs {} MiB, more than this device can allocate",
        per_sensor >> 20
    );
    ensure!(by_layers >= 1, "this device cannot render {layers} layers in one pass");
    Ok(by_layers.min((budget_bytes / per_sensor) as u32).max(1))
}

pub struct SensorMapPass {
    // Field order is drop order: users of an object before the object.
    pipeline: Pipeline,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    layout: PipelineLayout,
    framebuffer: Framebuffer,
    /// A framebuffer over the first layers only, for a last, smaller batch (so unused layers are not cleared).
    partial: Option<(u32, Framebuffer, ImageView, ImageView)>,
    maps: Image,
    depth: Image,
    render_pass: RenderPass,
    views: Buffer,
    view_layouts: Vec<ViewLayout>,
    layers: u32,
    batch: u32,
    near: f32,
}

impl SensorMapPass {
    /// Sensors of `kind`, `rd × rd` texels, up to `batch` per submission; `near` is the views' near plane.
    pub fn new(
        device: &Arc<Device>,
        scene: &GpuScene,
        kind: SensorKind,
        rd: u32,
        batch: u32,
        near: f32,
    ) -> Result<Self> {
        let features = device.adapter.features;
        ensure!(
            features.shader_output_layer,
            "{} cannot write gl_Layer from a vertex shader (shaderOutputLayer)",
            device.adapter
        );
        ensure!(
            features.shader_clip_distance || kind != SensorKind::Hemicube,
            "{} lacks clip distances, which hemicube sensors need; use --sensor frustum",
            device.adapter
        );
        kind.check_size(
            rd,
            device.adapter.limits.max_image_dimension_2d.min(device.adapter.limits.max_framebuffer_width),
        )?;
        let layers = kind.layers();
        let render_pass = RenderPass::new(device, &[MAP_FORMAT], Some(DEPTH_FORMAT), 0)?;
        let image = |name: &str, format, usage| {
            let desc = ImageDesc {
                format,
                width: rd,
                height: rd,
                layers: batch * layers,
                usage,
                view_type: vk::ImageViewType::TYPE_2D_ARRAY,
            };
            Image::new(device, name, desc)
        };
        let maps = image(
            "sensor maps",
            MAP_FORMAT,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
        )?;
        let depth = image("sensor depth", DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)?;
        // The reduction binds every layer; a smaller batch renders (and transitions) only the first ones, so
        // all layers start out in GENERAL.
        device.submit_and_wait(|cmd| {
            barrier::discard_to_general(device, cmd, maps.raw, maps.full_range(), vk::PipelineStageFlags::TOP_OF_PIPE);
            Ok(())
        })?;
        let framebuffer =
            Framebuffer::new(device, &render_pass, &[maps.view, depth.view], maps.extent(), batch * layers)?;

        let view_layouts = views(kind);
        let views = Buffer::new(
            device,
            "sensor views",
            (batch as usize * view_layouts.len() * size_of::<GpuSensorView>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let layout = PipelineLayout::new(
            device,
            &[(0, storage, vk::ShaderStageFlags::VERTEX), (1, storage, vk::ShaderStageFlags::VERTEX)],
            size_of::<SensorPush>() as u32,
            vk::ShaderStageFlags::VERTEX,
        )?;
        let pool = DescriptorPool::new(device, 1, &[(storage, 2)])?;
        let set = pool.allocate(&layout)?;
        SetWriter::new(set).storage_buffer(0, &views).storage_buffer(1, &scene.surfaces).apply(device);
        let pipeline = Pipeline::graphics(
            device,
            &layout,
            &GraphicsDesc {
                vertex: shaders::SENSOR_LAYERED_VERT,
                fragment: shaders::SENSOR_FRAG,
                render_pass: render_pass.raw,
                color_attachments: 1,
                vertex_stride: size_of::<Vertex>() as u32,
                vertex_attributes: &[
                    (0, vk::Format::R32G32B32_SFLOAT, VERTEX_POSITION_OFFSET),
                    (1, vk::Format::R32_UINT, VERTEX_SURFACE_OFFSET),
                ],
                depth_compare: Some(vk::CompareOp::GREATER),
            },
        )?;
        Ok(Self {
            pipeline,
            _pool: pool,
            set,
            layout,
            framebuffer,
            partial: None,
            maps,
            depth,
            render_pass,
            views,
            view_layouts,
            layers,
            batch,
            near,
        })
    }

    /// The sensor maps of the last batch, in `GENERAL` layout after the pass.
    pub fn maps(&self) -> &Image {
        &self.maps
    }

    pub fn batch(&self) -> u32 {
        self.batch
    }

    /// Writes the views of the next batch's sensors (the previous batch must be finished).
    pub fn set_sensors(&mut self, sensors: &[SensorFrame]) -> Result<()> {
        ensure!(sensors.len() as u32 <= self.batch, "{} sensors in a batch of {}", sensors.len(), self.batch);
        let (layouts, near, layers) = (&self.view_layouts, self.near, self.layers);
        let views: Vec<GpuSensorView> = sensors
            .iter()
            .enumerate()
            .flat_map(|(i, frame)| {
                layouts.iter().map(move |v| {
                    let clip = v.clip_horizon.then(|| frame.horizon());
                    GpuSensorView::new(frame.view_proj(v, near), clip, i as u32 * layers + v.layer)
                })
            })
            .collect();
        self.views.write(0, &views)
    }

    /// Records the render pass for the first `count` sensors set by [`SensorMapPass::set_sensors`].
    pub fn record(
        &mut self,
        device: &Arc<Device>,
        cmd: vk::CommandBuffer,
        scene: &GpuScene,
        count: u32,
        epsilon: f32,
        background: Vec3,
    ) -> Result<()> {
        let framebuffer = if count == self.batch {
            &self.framebuffer
        } else {
            if self.partial.as_ref().is_none_or(|p| p.0 != count) {
                // The previous partial framebuffer's batch has completed: replacing it is safe.
                let color = self.maps.layer_view(0, count * self.layers)?;
                let depth = self.depth.layer_view(0, count * self.layers)?;
                let fb = Framebuffer::new(
                    device,
                    &self.render_pass,
                    &[color.raw, depth.raw],
                    self.maps.extent(),
                    count * self.layers,
                )?;
                self.partial = Some((count, fb, color, depth));
            }
            &self.partial.as_ref().unwrap().1
        };
        let clears = [
            vk::ClearValue { color: vk::ClearColorValue { float32: background.extend(1.0).to_array() } },
            vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } },
        ];
        framebuffer.begin(cmd, &self.render_pass, &clears);
        let views = self.view_layouts.len() as u32;
        // SAFETY: recording state; every bound object outlives the submission (the caller waits on it).
        unsafe {
            device.raw.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline.raw);
            device.raw.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout.raw,
                0,
                &[self.set],
                &[],
            );
            device.raw.cmd_bind_vertex_buffers(cmd, 0, &[scene.vertices.raw], &[0]);
        }
        self.layout.push(cmd, &SensorPush { epsilon, first_view: 0, _pad: [0; 2] });
        // SAFETY: as above.
        unsafe {
            device.raw.cmd_draw(cmd, scene.vertex_count, count * views, 0, 0);
            device.raw.cmd_end_render_pass(cmd);
        }
        Ok(())
    }
}
