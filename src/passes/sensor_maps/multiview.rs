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

use anyhow::{Result, ensure};

use super::{CkParams, MapLayout, SensorPipeline, SlotMaps, Strategy, StrategyDesc};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::{GpuSensorView, SensorPush};
use crate::sensors::views::BatchViews;
use crate::shaders;
use crate::strategy::StrategyKind;
use crate::vk::{Device, Encoder};

pub struct Multiview {
    pipeline: SensorPipeline,
    /// For each layer of a sensor, the indices of its views that draw into it, in draw order.
    per_layer: Vec<Vec<usize>>,
    desc: StrategyDesc,
    /// Layers per group (bits in the view mask), sensors per group, and groups per batch.
    group_layers: u32,
    group_sensors: u32,
    groups: u32,
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
            .min(desc.batch_limit(device, super::DrawBytes::default())?.div_ceil(group_sensors))
            .max(1);
        let view_layers = desc.layout.view_layers();
        let per_layer: Vec<Vec<usize>> =
            (0..layers).map(|l| (0..view_layers.len()).filter(|&v| view_layers[v] == l).collect()).collect();
        let view_mask = if group_layers == 32 { u32::MAX } else { (1 << group_layers) - 1 };
        // Full detail: a multiview draw serves k views at once, so there is no one view's list to draw.
        let pipeline = SensorPipeline::new(
            device,
            scene,
            &desc,
            ([shaders::SENSOR_MULTIVIEW_VERT, shaders::SENSOR_MULTIVIEW_VERT_TEXTURES], view_mask),
            false,
        )?;
        Ok(Self { pipeline, per_layer, desc, group_layers, group_sensors, groups })
    }

    fn draws(&self) -> u32 {
        self.per_layer.iter().map(Vec::len).max().unwrap_or(1) as u32
    }

    /// Views, group-major then draw-major: entry `(g·draws + d)·k + j` is what draw d of group g shows in
    /// the group's layer j.
    fn views(&self, batch: &BatchViews) -> Vec<GpuSensorView> {
        let (k, layers) = (self.group_layers, self.desc.layers());
        let groups = (batch.len() as u32).div_ceil(self.group_sensors);
        let mut out = Vec::with_capacity((groups * self.draws() * k) as usize);
        for g in 0..groups {
            for d in 0..self.draws() as usize {
                for j in 0..k {
                    let sensor = (g * self.group_sensors + j / layers) as usize;
                    let view = self.per_layer[(j % layers) as usize].get(d).filter(|_| sensor < batch.len());
                    out.push(match view {
                        Some(&v) => GpuSensorView { layer: j, ..batch.of(sensor)[v] },
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
        self.groups * self.group_sensors
    }

    fn map_layout(&self) -> MapLayout {
        MapLayout::Layers
    }

    fn new_slot(&self) -> Result<SlotMaps> {
        let (rd, k) = (self.desc.rd, self.group_layers);
        let max_views = (self.groups * k * self.draws()) as usize;
        let mut slot = SlotMaps::new(&self.pipeline, (rd, rd, self.groups * k), max_views)?;
        // Multiview framebuffers have one layer; the view mask addresses the attachments' layers.
        slot.framebuffers =
            (0..self.groups).map(|g| slot.layer_framebuffer(&self.pipeline, (g * k, k), 1)).collect::<Result<_>>()?;
        Ok(slot)
    }

    fn record(&self, enc: &Encoder<'_>, slot: &mut SlotMaps, batch: &BatchViews, ck: CkParams) -> Result<()> {
        slot.views.write(0, &self.views(batch))?;
        let groups = (batch.len() as u32).div_ceil(self.group_sensors);
        let (draws, k) = (self.draws(), self.group_layers);
        for g in 0..groups {
            let pass = self.pipeline.begin(enc, slot, &slot.framebuffers[g as usize], ck, None);
            for d in 0..draws {
                let push = SensorPush { first_view: (g * draws + d) * k, ..ck.push() };
                self.pipeline.draw(&pass, &push, 1, 0);
            }
        }
        Ok(())
    }
}
