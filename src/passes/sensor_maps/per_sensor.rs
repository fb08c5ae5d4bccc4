//! One render pass per sensor, over that sensor's own layers: either each in its own submission followed by
//! its reduction (`per-sensor`, the paper's DX9 loop, the baseline), or all of a batch recorded into one
//! command buffer (`single-cb`). Same layer layout as the layered strategy.

use std::sync::Arc;
use std::time::Duration;

use anyhow::{Result, ensure};

use super::{LayerFramebuffer, MapImages, SenseContext, SensorPipeline, Strategy, StrategyDesc, StrategyKind};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::SensorPush;
use crate::sensors::frame::SensorFrame;
use crate::sensors::layout::{ViewLayout, views};
use crate::shaders;
use crate::vk::{Device, Image};

pub struct PerSensor {
    // Field order is drop order: framebuffers before the views and images they use.
    framebuffers: Vec<LayerFramebuffer>,
    pipeline: SensorPipeline,
    images: MapImages,
    layouts: Vec<ViewLayout>,
    desc: StrategyDesc,
    /// `single-cb`: every sensor of a batch in one submission.
    one_submission: bool,
}

impl PerSensor {
    pub fn new(device: &Arc<Device>, scene: &GpuScene, desc: StrategyDesc, one_submission: bool) -> Result<Self> {
        let limits = &device.adapter.limits;
        let layers = desc.layers();
        ensure!(limits.max_framebuffer_layers >= layers, "this device cannot render {layers} layers in one pass");
        let capacity = (limits.max_image_array_layers / layers).min(desc.sensors_in_budget(device)?);
        let layouts = views(desc.sensor);
        let pipeline =
            SensorPipeline::new(device, scene, shaders::SENSOR_LAYERED_VERT, 0, (capacity as usize) * layouts.len())?;
        let images = MapImages::new(device, desc.rd, desc.rd, capacity * layers)?;
        let framebuffers = (0..capacity)
            .map(|i| images.layer_framebuffer(device, &pipeline.render_pass, (i * layers, layers), layers))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self { framebuffers, pipeline, images, layouts, desc, one_submission })
    }
}

impl Strategy for PerSensor {
    fn kind(&self) -> StrategyKind {
        if self.one_submission { StrategyKind::SingleCb } else { StrategyKind::PerSensor }
    }

    fn capacity(&self) -> u32 {
        self.framebuffers.len() as u32
    }

    fn maps(&self) -> (&Image, u32) {
        (&self.images.maps, 0)
    }

    fn sense(&mut self, ctx: &SenseContext<'_>, frames: &[SensorFrame]) -> Result<Duration> {
        let layers = self.desc.layers();
        self.pipeline.write_views(frames, &self.layouts, self.desc.near, |i, v| i * layers + v.layer)?;
        let (device, pipeline) = (ctx.device, &self.pipeline);
        let per_sensor = self.layouts.len() as u32;
        let clears = MapImages::clears(ctx.background);
        // Sensor i: its own framebuffer, its views, gl_Layer relative to its first layer.
        let record_sensor = |cmd, i: u32| {
            self.framebuffers[i as usize].framebuffer.begin(cmd, &pipeline.render_pass, &clears);
            pipeline.bind(device, cmd, ctx.scene);
            let push = SensorPush { epsilon: ctx.epsilon, layer_base: i * layers, ..Default::default() };
            pipeline.draw(device, cmd, ctx.scene, &push, per_sensor, i * per_sensor);
            // SAFETY: recording state, inside the render pass begun above.
            unsafe { device.raw.cmd_end_render_pass(cmd) };
        };
        let count = frames.len() as u32;
        if self.one_submission {
            return device.submit_and_wait(|cmd| {
                (0..count).for_each(|i| record_sensor(cmd, i));
                ctx.reduce.record(device, cmd, 0, count);
                Ok(())
            });
        }
        let mut time = Duration::ZERO;
        for i in 0..count {
            time += device.submit_and_wait(|cmd| {
                record_sensor(cmd, i);
                ctx.reduce.record(device, cmd, i, 1);
                Ok(())
            })?;
        }
        Ok(time)
    }
}
