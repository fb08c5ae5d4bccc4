//! Raw fill pass: full-screen triangles into every layer of an `rd × rd` 2D array in the sensor maps'
//! colour and depth formats, cleared first as the sensor passes are. What a device can fill per second this
//! way is the ceiling the benchmark compares the sensor strategies with. Shaders: `glsl/fill.*`.

use std::sync::Arc;
use std::time::Duration;

use anyhow::Result;
use ash::vk;

use super::DEPTH_FORMAT;
use super::sensor_maps::MAP_FORMAT;
use crate::shaders;
use crate::vk::{Device, Framebuffer, GraphicsDesc, Image, ImageDesc, ImageView, Pipeline, PipelineLayout, RenderPass};

pub struct FillPass {
    pipeline: Pipeline,
    _layout: PipelineLayout,
    framebuffer: Framebuffer,
    render_pass: RenderPass,
    layers: u32,
}

impl FillPass {
    pub fn new(device: &Arc<Device>, rd: u32, layers: u32) -> Result<Self> {
        let render_pass = RenderPass::new(device, &[MAP_FORMAT], Some(DEPTH_FORMAT), 0)?;
        let desc = |format, usage| ImageDesc {
            format,
            width: rd,
            height: rd,
            layers,
            usage,
            view_type: vk::ImageViewType::TYPE_2D_ARRAY,
        };
        let color = Image::new(device, "fill colour", desc(MAP_FORMAT, vk::ImageUsageFlags::COLOR_ATTACHMENT))?;
        let depth =
            Image::new(device, "fill depth", desc(DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT))?;
        let attachments = vec![ImageView::whole(&Arc::new(color))?, ImageView::whole(&Arc::new(depth))?];
        let framebuffer = Framebuffer::new(device, &render_pass, attachments, layers)?;
        let layout = PipelineLayout::new(device, &[], 0, vk::ShaderStageFlags::VERTEX)?;
        let pipeline = Pipeline::graphics(
            device,
            &layout,
            &GraphicsDesc {
                vertex: shaders::FILL_VERT,
                vertex_constants: &[],
                fragment: shaders::FILL_FRAG,
                render_pass: render_pass.raw,
                color_attachments: 1,
                vertex_stride: 0,
                vertex_attributes: &[],
                depth_compare: Some(vk::CompareOp::GREATER),
            },
        )?;
        Ok(Self { pipeline, _layout: layout, framebuffer, render_pass, layers })
    }

    /// Clears and fills every layer once; returns the time from submission to completion.
    pub fn run(&self, device: &Arc<Device>) -> Result<Duration> {
        let clears = [
            vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } },
            vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } },
        ];
        device.submit_and_wait(|enc| {
            let pass = enc.begin_render_pass(&self.render_pass, &self.framebuffer, &clears, None);
            pass.bind_pipeline(&self.pipeline); // no descriptors
            pass.draw(3, self.layers, 0, 0);
            Ok(())
        })
    }
}
