//! Multiview strategy (`VK_KHR_multiview`, core in Vulkan 1.1). A render pass whose view mask has k bits
//! set runs each draw k times, `gl_ViewIndex` = 0…k−1, and view i always writes layer i of the attachments
//! (which must be 2D-array views with a framebuffer of one layer). So a group of k layers holds k / layers
//! sensors, and the shader picks its view from a table indexed by `gl_ViewIndex`.
//!
//! A hemicube puts two views (±t, ±b) into layers 1 and 2 but one (front) into layer 0, so each group is
//! drawn twice: the first table holds front, +t, +b per sensor, the second nothing, −t, −b ("nothing" is a
//! view whose clip plane rejects everything).
//!
//! ```text
//!   group g (k = 6, hemicube):  layer  | s0 L0 | s0 L1 | s0 L2 | s1 L0 | s1 L1 | s1 L2 |
//!                               draw 1 | front |  +t   |  +b   | front |  +t   |  +b   |
//!                               draw 2 |   –   |  −t   |  −b   |   –   |  −t   |  −b   |
//! ```

use std::sync::Arc;
use std::time::Duration;

use anyhow::{Result, ensure};

use super::{LayerFramebuffer, MapImages, SenseContext, SensorPipeline, Strategy, StrategyDesc, StrategyKind};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::{GpuSensorView, SensorPush};
use crate::sensors::frame::SensorFrame;
use crate::sensors::layout::{ViewLayout, views};
use crate::shaders;
use crate::vk::{Device, Image};

pub struct Multiview {
    // Field order is drop order: framebuffers before the views and images they use.
    framebuffers: Vec<LayerFramebuffer>,
    pipeline: SensorPipeline,
    images: MapImages,
    /// For each layer of a sensor, the views that draw into it, in draw order.
    per_layer: Vec<Vec<ViewLayout>>,
    desc: StrategyDesc,
    /// Layers per group (bits in the view mask) and sensors per group.
    group_layers: u32,
    group_sensors: u32,
}

impl Multiview {
    pub fn new(device: &Arc<Device>, scene: &GpuScene, desc: StrategyDesc) -> Result<Self> {
        let limits = &device.adapter.limits;
        let layers = desc.layers();
        // View masks are 32 bits wide.
        let group_sensors = limits.max_multiview_view_count.min(32) / layers;
        ensure!(group_sensors >= 1, "maxMultiviewViewCount {} < {layers}", limits.max_multiview_view_count);
        let group_layers = group_sensors * layers;
        let groups = (limits.max_image_array_layers / group_layers)
            .min(desc.sensors_in_budget(device)?.div_ceil(group_sensors))
            .max(1);
        let layouts = views(desc.sensor);
        let per_layer: Vec<Vec<ViewLayout>> =
            (0..layers).map(|l| layouts.iter().copied().filter(|v| v.layer == l).collect()).collect();
        let draws = per_layer.iter().map(Vec::len).max().unwrap_or(1);
        let view_mask = if group_layers == 32 { u32::MAX } else { (1 << group_layers) - 1 };
        let max_views = (groups * group_layers) as usize * draws;
        let pipeline = SensorPipeline::new(device, scene, shaders::SENSOR_MULTIVIEW_VERT, view_mask, max_views)?;
        let images = MapImages::new(device, desc.rd, desc.rd, groups * group_layers)?;
        // Multiview framebuffers have one layer; the view mask addresses the attachments' layers.
        let framebuffers = (0..groups)
            .map(|g| images.layer_framebuffer(device, &pipeline.render_pass, (g * group_layers, group_layers), 1))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self { framebuffers, pipeline, images, per_layer, desc, group_layers, group_sensors })
    }

    fn draws(&self) -> u32 {
        self.per_layer.iter().map(Vec::len).max().unwrap_or(1) as u32
    }

    /// Views, group-major then draw-major: entry `(g·draws + d)·k + j` is what draw d of group g shows in
    /// the group's layer j.
    fn views(&self, frames: &[SensorFrame]) -> Vec<GpuSensorView> {
        let (k, layers, near) = (self.group_layers, self.desc.layers(), self.desc.near);
        let groups = (frames.len() as u32).div_ceil(self.group_sensors);
        let mut out = Vec::with_capacity((groups * self.draws() * k) as usize);
        for g in 0..groups {
            for d in 0..self.draws() as usize {
                for j in 0..k {
                    let sensor = (g * self.group_sensors + j / layers) as usize;
                    let view = frames.get(sensor).zip(self.per_layer[(j % layers) as usize].get(d));
                    out.push(match view {
                        Some((frame, v)) => {
                            GpuSensorView::new(frame.view_proj(v, near), v.clip_horizon.then(|| frame.horizon()), j)
                        }
                        None => GpuSensorView::empty(j),
                    });
                }
            }
        }
        out
    }
}

impl Strategy for Multiview {
    fn kind(&self) -> StrategyKind {
        StrategyKind::Multiview
    }

    fn capacity(&self) -> u32 {
        self.framebuffers.len() as u32 * self.group_sensors
    }

    fn maps(&self) -> (&Image, u32) {
        (&self.images.maps, 0)
    }

    fn sense(&mut self, ctx: &SenseContext<'_>, frames: &[SensorFrame]) -> Result<Duration> {
        self.pipeline.views.write(0, &self.views(frames))?;
        let (device, pipeline) = (ctx.device, &self.pipeline);
        let count = frames.len() as u32;
        let groups = count.div_ceil(self.group_sensors);
        let (draws, k) = (self.draws(), self.group_layers);
        let clears = MapImages::clears(ctx.background);
        device.submit_and_wait(|cmd| {
            for g in 0..groups {
                self.framebuffers[g as usize].framebuffer.begin(cmd, &pipeline.render_pass, &clears);
                pipeline.bind(device, cmd, ctx.scene);
                for d in 0..draws {
                    let push =
                        SensorPush { epsilon: ctx.epsilon, first_view: (g * draws + d) * k, ..Default::default() };
                    pipeline.draw(device, cmd, ctx.scene, &push, 1, 0);
                }
                // SAFETY: recording state, inside the render pass begun above.
                unsafe { device.raw.cmd_end_render_pass(cmd) };
            }
            ctx.reduce.record(device, cmd, 0, count);
            Ok(())
        })
    }
}
