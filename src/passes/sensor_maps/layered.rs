//! Layered strategy: a batch is one render pass over a framebuffer of `sensors × layers` layers and one
//! instanced draw, an instance per sensor view, `gl_Layer` chosen in the vertex shader.
//!
//! ```text
//!   maps (2D array, rd × rd per layer):  | s0 L0 | s0 L1 | s0 L2 | s1 L0 | s1 L1 | … |   (hemicube: 3 per sensor)
//! ```

use std::sync::Arc;
use std::time::Duration;

use anyhow::{Result, ensure};

use super::{LayerFramebuffer, MapImages, SenseContext, SensorPipeline, Strategy, StrategyDesc, StrategyKind};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::SensorPush;
use crate::sensors::frame::SensorFrame;
use crate::sensors::layout::{ViewLayout, views};
use crate::shaders;
use crate::vk::{Device, Framebuffer, Image};

pub struct Layered {
    // Field order is drop order: framebuffers before the images they view.
    framebuffer: Framebuffer,
    /// A framebuffer over the first layers only, for a smaller batch (so unused layers are not cleared).
    partial: Option<(u32, LayerFramebuffer)>,
    pipeline: SensorPipeline,
    images: MapImages,
    layouts: Vec<ViewLayout>,
    desc: StrategyDesc,
    capacity: u32,
}

impl Layered {
    pub fn new(device: &Arc<Device>, scene: &GpuScene, desc: StrategyDesc) -> Result<Self> {
        let limits = &device.adapter.limits;
        let layers = desc.layers();
        let by_layers = limits.max_framebuffer_layers.min(limits.max_image_array_layers) / layers;
        ensure!(by_layers >= 1, "this device cannot render {layers} layers in one pass");
        let capacity = by_layers.min(desc.sensors_in_budget(device)?);
        let layouts = views(desc.sensor);
        let pipeline =
            SensorPipeline::new(device, scene, shaders::SENSOR_LAYERED_VERT, 0, (capacity as usize) * layouts.len())?;
        let images = MapImages::new(device, desc.rd, desc.rd, capacity * layers)?;
        let extent = images.maps.extent();
        let framebuffer = Framebuffer::new(
            device,
            &pipeline.render_pass,
            &[images.maps.view, images.depth.view],
            extent,
            capacity * layers,
        )?;
        Ok(Self { framebuffer, partial: None, pipeline, images, layouts, desc, capacity })
    }

    /// Makes sure a framebuffer over the first `count` sensors exists (see [`Layered::framebuffer`]).
    fn prepare_framebuffer(&mut self, device: &Arc<Device>, count: u32) -> Result<()> {
        if count != self.capacity && self.partial.as_ref().is_none_or(|p| p.0 != count) {
            // The previous partial framebuffer's batch has completed (sense waits): replacing it is safe.
            let layers = count * self.desc.layers();
            let fb = self.images.layer_framebuffer(device, &self.pipeline.render_pass, (0, layers), layers)?;
            self.partial = Some((count, fb));
        }
        Ok(())
    }

    fn framebuffer(&self, count: u32) -> &Framebuffer {
        match &self.partial {
            Some((n, fb)) if *n == count && count != self.capacity => &fb.framebuffer,
            _ => &self.framebuffer,
        }
    }
}

impl Strategy for Layered {
    fn kind(&self) -> StrategyKind {
        StrategyKind::Layered
    }

    fn capacity(&self) -> u32 {
        self.capacity
    }

    fn maps(&self) -> (&Image, u32) {
        (&self.images.maps, 0)
    }

    fn sense(&mut self, ctx: &SenseContext<'_>, frames: &[SensorFrame]) -> Result<Duration> {
        let layers = self.desc.layers();
        self.pipeline.write_views(frames, &self.layouts, self.desc.near, |i, v| i * layers + v.layer)?;
        let count = frames.len() as u32;
        let device = ctx.device;
        self.prepare_framebuffer(device, count)?;
        let framebuffer = self.framebuffer(count);
        let (pipeline, view_count) = (&self.pipeline, self.layouts.len() as u32);
        let push = SensorPush { epsilon: ctx.epsilon, ..Default::default() };
        device.submit_and_wait(|cmd| {
            framebuffer.begin(cmd, &pipeline.render_pass, &MapImages::clears(ctx.background));
            pipeline.bind(device, cmd, ctx.scene);
            pipeline.draw(device, cmd, ctx.scene, &push, count * view_count, 0);
            // SAFETY: recording state, inside the render pass begun above.
            unsafe { device.raw.cmd_end_render_pass(cmd) };
            ctx.reduce.record(device, cmd, 0, count);
            Ok(())
        })
    }
}
