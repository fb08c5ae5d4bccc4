//! G-buffer pass (paper §III-F, docs/DESIGN.md §3 step 1): rasterises the scene from the camera into world
//! position, normal, albedo, emission and surface id at the output resolution. Shaders: `glsl/gbuffer.*`.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use glam::Vec4;

use super::{DEPTH_COMPARE, DEPTH_FORMAT};
use crate::gbuffer::GBufferData;
use crate::gpu_scene::GpuScene;
use crate::gpu_types::{GBufferPush, VERTEX_ATTRIBUTES, VERTEX_STRIDE};
use crate::scene::{Camera, ImageSize};
use crate::shaders;
use crate::vk::{
    DescriptorPool, Device, Framebuffer, GraphicsDesc, Image, ImageDesc, ImageView, Pipeline, PipelineLayout,
    RenderPass, SetWriter, transfer,
};

/// Colour attachments, in shader output order: position, normal, albedo, emission, surface id.
pub const ATTACHMENT_COUNT: u32 = 5;
pub const COLOR_FORMATS: [vk::Format; ATTACHMENT_COUNT as usize] = [
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R32_UINT,
];

/// Camera near plane as a fraction of the scene's diagonal (reversed-Z: precision does not need it larger).
pub const NEAR: f32 = 1e-3;

pub struct GBufferPass {
    // Field order is drop order: the pipeline before its layout and render pass.
    pipeline: Pipeline,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    layout: PipelineLayout,
    render_pass: RenderPass,
}

/// The G-buffer images on the GPU, each in `GENERAL` layout after [`GBufferPass::render`].
pub struct GBuffer {
    pub position: Arc<Image>,
    pub normal: Arc<Image>,
    pub albedo: Arc<Image>,
    pub emission: Arc<Image>,
    pub surface: Arc<Image>,
    pub size: ImageSize,
}

impl GBufferPass {
    pub fn new(device: &Arc<Device>, scene: &GpuScene) -> Result<Self> {
        let render_pass = RenderPass::new(device, &COLOR_FORMATS, Some(DEPTH_FORMAT), 0)?;
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let layout = PipelineLayout::new(
            device,
            &[
                (0, storage, vk::ShaderStageFlags::FRAGMENT),
                (1, storage, vk::ShaderStageFlags::VERTEX),
                (2, storage, vk::ShaderStageFlags::VERTEX),
                (3, storage, vk::ShaderStageFlags::FRAGMENT),
                (4, storage, vk::ShaderStageFlags::FRAGMENT),
            ],
            size_of::<GBufferPush>() as u32,
            vk::ShaderStageFlags::VERTEX,
        )?;
        let pool = DescriptorPool::new(device, 1, &[(storage, 5)])?;
        let set = pool.allocate(&layout)?;
        SetWriter::new(set)
            .storage_buffer(0, &scene.surfaces)
            .storage_buffer(1, &scene.normals)
            .storage_buffer(2, &scene.uvs)
            .storage_buffer(3, &scene.textures)
            .storage_buffer(4, &scene.texels)
            .apply(device);
        let pipeline = Pipeline::graphics(
            device,
            &layout,
            &GraphicsDesc {
                vertex: shaders::GBUFFER_VERT,
                vertex_constants: &[],
                fragment: shaders::GBUFFER_FRAG,
                render_pass: render_pass.raw,
                color_attachments: ATTACHMENT_COUNT,
                vertex_stride: VERTEX_STRIDE,
                vertex_attributes: &VERTEX_ATTRIBUTES,
                depth_compare: Some(DEPTH_COMPARE),
            },
        )?;
        Ok(Self { pipeline, _pool: pool, set, layout, render_pass })
    }

    /// Renders the G-buffer of `scene` seen by `camera` at `size`; `near` is the camera's near plane distance.
    pub fn render(
        &self,
        device: &Arc<Device>,
        scene: &GpuScene,
        camera: &Camera,
        size: ImageSize,
        near: f32,
    ) -> Result<GBuffer> {
        let limits = &device.adapter.limits;
        anyhow::ensure!(
            size.width <= limits.max_framebuffer_width && size.height <= limits.max_framebuffer_height,
            "image {}x{} exceeds this device's largest framebuffer ({}x{})",
            size.width,
            size.height,
            limits.max_framebuffer_width,
            limits.max_framebuffer_height
        );
        let image = |name: &str, format: vk::Format, usage: vk::ImageUsageFlags| -> Result<Arc<Image>> {
            let desc = ImageDesc {
                format,
                width: size.width,
                height: size.height,
                layers: 1,
                usage,
                view_type: vk::ImageViewType::TYPE_2D,
            };
            Ok(Arc::new(Image::new(device, name, desc)?))
        };
        let color =
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let [position, normal, albedo, emission, surface] = [
            image("gbuffer position", COLOR_FORMATS[0], color)?,
            image("gbuffer normal", COLOR_FORMATS[1], color)?,
            image("gbuffer albedo", COLOR_FORMATS[2], color)?,
            image("gbuffer emission", COLOR_FORMATS[3], color)?,
            image("gbuffer surface id", COLOR_FORMATS[4], color)?,
        ];
        let depth = image("gbuffer depth", DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)?;
        let attachments = [&position, &normal, &albedo, &emission, &surface, &depth]
            .into_iter()
            .map(ImageView::whole)
            .collect::<Result<Vec<_>>>()?;
        // Dropped at the end of this function: the submission below is waited on.
        let framebuffer = Framebuffer::new(device, &self.render_pass, attachments, 1)?;

        let push = GBufferPush { view_proj: camera.view_proj(size.width, size.height, near) };
        let zero = vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } };
        let clears = [
            zero,
            zero,
            zero,
            zero,
            vk::ClearValue { color: vk::ClearColorValue { uint32: [0; 4] } },
            vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } },
        ];
        device.submit_and_wait(|enc| {
            let pass = enc.begin_render_pass(&self.render_pass, &framebuffer, &clears, None);
            pass.bind(&self.pipeline, &self.layout, self.set);
            pass.bind_vertices(&scene.vertices);
            pass.push(&self.layout, &push);
            pass.draw(scene.vertex_count, 1, 0, 0);
            Ok(())
        })?;
        Ok(GBuffer { position, normal, albedo, emission, surface, size })
    }
}

impl GBuffer {
    pub fn read_back(&self, device: &Arc<Device>) -> Result<GBufferData> {
        let vec4s = |image: &Image| -> Result<Vec<Vec4>> {
            Ok(transfer::read_image::<[f32; 4]>(device, image)?.into_iter().map(Vec4::from).collect())
        };
        Ok(GBufferData {
            size: self.size,
            position: vec4s(&self.position)?,
            normal: vec4s(&self.normal)?,
            albedo: vec4s(&self.albedo)?,
            emission: vec4s(&self.emission)?,
            surface: transfer::read_image::<u32>(device, &self.surface)?,
        })
    }
}
