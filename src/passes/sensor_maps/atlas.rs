//! Atlas strategy (ours): every sensor layer is an `rd × rd` tile of one large 2D image, filled by one
//! instanced draw that squeezes each view into its tile in clip space (`glsl/sensor_atlas.vert`).
//!
//! Why: a layered framebuffer is drawn layer after layer, and each layer is a separate small target; at
//! small rd a rasteriser that bins into fixed-size screen tiles (lavapipe's are 64 × 64) then works on
//! mostly empty tiles with per-layer overheads. One large target keeps every binning tile full and its
//! worker threads busy, and a smaller batch clears only the rows it uses.

use std::sync::Arc;
use std::time::Duration;

use anyhow::{Result, ensure};
use ash::vk;

use super::{MapImages, SenseContext, SensorPipeline, Strategy, StrategyDesc, StrategyKind};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::SensorPush;
use crate::sensors::frame::SensorFrame;
use crate::sensors::layout::{ViewLayout, views};
use crate::shaders;
use crate::vk::{Device, Framebuffer, Image};

pub struct Atlas {
    framebuffer: Framebuffer,
    pipeline: SensorPipeline,
    images: MapImages,
    layouts: Vec<ViewLayout>,
    desc: StrategyDesc,
    columns: u32,
    rows: u32,
    capacity: u32,
}

impl Atlas {
    pub fn new(device: &Arc<Device>, scene: &GpuScene, desc: StrategyDesc) -> Result<Self> {
        let l = &device.adapter.limits;
        let layers = desc.layers();
        let (max_w, max_h) = (
            l.max_framebuffer_width.min(l.max_image_dimension_2d),
            l.max_framebuffer_height.min(l.max_image_dimension_2d),
        );
        let (max_columns, max_rows) = (max_w / desc.rd, max_h / desc.rd);
        ensure!(
            max_columns * max_rows >= layers,
            "an atlas of {layers} tiles of {}² does not fit a framebuffer",
            desc.rd
        );
        let capacity = (max_columns * max_rows / layers).min(desc.sensors_in_budget(device)?).max(1);
        let tiles = capacity * layers;
        let columns = tiles.min(max_columns);
        let rows = tiles.div_ceil(columns);
        let layouts = views(desc.sensor);
        let pipeline =
            SensorPipeline::new(device, scene, shaders::SENSOR_ATLAS_VERT, 0, (capacity as usize) * layouts.len())?;
        let images = MapImages::new(device, columns * desc.rd, rows * desc.rd, 1)?;
        let framebuffer = Framebuffer::new(
            device,
            &pipeline.render_pass,
            &[images.maps.view, images.depth.view],
            images.maps.extent(),
            1,
        )?;
        Ok(Self { framebuffer, pipeline, images, layouts, desc, columns, rows, capacity })
    }
}

impl Strategy for Atlas {
    fn kind(&self) -> StrategyKind {
        StrategyKind::Atlas
    }

    fn capacity(&self) -> u32 {
        self.capacity
    }

    fn maps(&self) -> (&Image, u32) {
        (&self.images.maps, self.columns)
    }

    fn sense(&mut self, ctx: &SenseContext<'_>, frames: &[SensorFrame]) -> Result<Duration> {
        let layers = self.desc.layers();
        self.pipeline.write_views(frames, &self.layouts, self.desc.near, |i, v| i * layers + v.layer)?;
        let count = frames.len() as u32;
        let (device, pipeline) = (ctx.device, &self.pipeline);
        // Only the rows of tiles this batch uses are cleared and drawn.
        let rows_used = (count * layers).div_ceil(self.columns);
        let area = vk::Extent2D { width: self.columns * self.desc.rd, height: rows_used * self.desc.rd };
        let push = SensorPush {
            epsilon: ctx.epsilon,
            atlas_columns: self.columns,
            atlas_rows: self.rows,
            ..Default::default()
        };
        let view_count = self.layouts.len() as u32;
        device.submit_and_wait(|cmd| {
            self.framebuffer.begin_area(cmd, &pipeline.render_pass, &MapImages::clears(ctx.background), area);
            pipeline.bind(device, cmd, ctx.scene);
            pipeline.draw(device, cmd, ctx.scene, &push, count * view_count, 0);
            // SAFETY: recording state, inside the render pass begun above.
            unsafe { device.raw.cmd_end_render_pass(cmd) };
            ctx.reduce.record(device, cmd, 0, count);
            Ok(())
        })
    }
}
