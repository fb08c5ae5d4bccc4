//! Layered strategy: a batch is one render pass over a framebuffer of `sensors × layers` layers and one
//! instanced draw, an instance per sensor view, `gl_Layer` chosen in the vertex shader.
//!
//! ```text
//!   maps (2D array, rd × rd per layer):  | s0 L0 | s0 L1 | s0 L2 | s1 L0 | s1 L1 | … |   (hemicube: 3 per sensor)
//! ```

use std::sync::Arc;

use anyhow::{Result, ensure};

use super::{CkParams, MapLayout, SensorPipeline, SlotMaps, Strategy, StrategyDesc};
use crate::gpu_scene::GpuScene;
use crate::sensors::views::BatchViews;
use crate::shaders;
use crate::strategy::StrategyKind;
use crate::vk::{Device, Encoder};

pub struct Layered {
    pipeline: SensorPipeline,
    desc: StrategyDesc,
    capacity: u32,
}

impl Layered {
    pub fn new(device: &Arc<Device>, scene: &GpuScene, desc: StrategyDesc) -> Result<Self> {
        let limits = &device.adapter.limits;
        let layers = desc.layers();
        let by_layers = limits.max_framebuffer_layers.min(limits.max_image_array_layers) / layers;
        ensure!(by_layers >= 1, "this device cannot render {layers} layers in one pass");
        let pipeline = SensorPipeline::new(
            device,
            scene,
            &desc,
            ([shaders::SENSOR_LAYERED_VERT, shaders::SENSOR_LAYERED_VERT_TEXTURES], 0),
            true,
        )?;
        let capacity = by_layers.min(desc.batch_limit(device, pipeline.draw_bytes(&desc))?);
        Ok(Self { pipeline, desc, capacity })
    }
}

impl Strategy for Layered {
    fn kind(&self) -> StrategyKind {
        StrategyKind::Layered
    }

    fn capacity(&self) -> u32 {
        self.capacity
    }

    fn map_layout(&self) -> MapLayout {
        MapLayout::Layers
    }

    fn new_slot(&self) -> Result<SlotMaps> {
        let (rd, layers) = (self.desc.rd, self.capacity * self.desc.layers());
        let views = self.capacity as usize * self.desc.layout.views() as usize;
        let mut slot = SlotMaps::new(&self.pipeline, (rd, rd, layers), views)?;
        slot.framebuffers = vec![slot.whole_framebuffer(&self.pipeline)?];
        Ok(slot)
    }

    fn record(&self, enc: &Encoder<'_>, slot: &mut SlotMaps, batch: &BatchViews, ck: CkParams) -> Result<()> {
        let layers = self.desc.layers();
        slot.write_views(batch, |i, layer| i * layers + layer)?;
        let count = batch.len() as u32;
        // A smaller batch draws into a framebuffer over its own layers only, so that the others are not
        // cleared. The previous one's batch has completed (the runner waited for the slot): replacing it is safe.
        if count != self.capacity && slot.partial.as_ref().is_none_or(|p| p.0 != count) {
            let partial = slot.layer_framebuffer(&self.pipeline, (0, count * layers), count * layers)?;
            slot.partial = Some((count, partial));
        }
        let framebuffer = match &slot.partial {
            Some((n, fb)) if *n == count => fb,
            _ => &slot.framebuffers[0],
        };
        let pass = self.pipeline.begin(enc, slot, framebuffer, ck, None);
        let push = ck.push();
        self.pipeline.draw_views(&pass, slot, &push, (0, count * batch.per_sensor as u32));
        Ok(())
    }
}
