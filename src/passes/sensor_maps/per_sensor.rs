//! One render pass per sensor, over that sensor's own layers: either one sensor per batch, so one
//! submission per sensor with its reduction (`per-sensor`, the paper's DX9 loop, the baseline), or a batch
//! of sensors recorded into one command buffer (`single-cb`). Same layer layout as the layered strategy.

use std::sync::Arc;

use anyhow::{Result, ensure};

use super::{CkParams, MapLayout, SensorPipeline, SlotMaps, Strategy, StrategyDesc};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::SensorPush;
use crate::sensors::views::BatchViews;
use crate::shaders;
use crate::strategy::StrategyKind;
use crate::vk::{Device, Encoder};

pub struct PerSensor {
    pipeline: SensorPipeline,
    desc: StrategyDesc,
    capacity: u32,
    /// `single-cb`: a batch of sensors per submission; else one.
    one_submission: bool,
}

impl PerSensor {
    pub fn new(device: &Arc<Device>, scene: &GpuScene, desc: StrategyDesc, one_submission: bool) -> Result<Self> {
        let limits = &device.adapter.limits;
        let layers = desc.layers();
        ensure!(limits.max_framebuffer_layers >= layers, "this device cannot render {layers} layers in one pass");
        let pipeline = SensorPipeline::new(
            device,
            scene,
            &desc,
            ([shaders::SENSOR_LAYERED_VERT, shaders::SENSOR_LAYERED_VERT_TEXTURES], 0),
            true,
        )?;
        let draw_bytes = pipeline.draw_bytes(&desc);
        let capacity = if one_submission {
            (limits.max_image_array_layers / layers).min(desc.batch_limit(device, draw_bytes)?)
        } else {
            1
        };
        Ok(Self { pipeline, desc, capacity, one_submission })
    }
}

impl Strategy for PerSensor {
    fn kind(&self) -> StrategyKind {
        if self.one_submission { StrategyKind::SingleCb } else { StrategyKind::PerSensor }
    }

    fn capacity(&self) -> u32 {
        self.capacity
    }

    fn map_layout(&self) -> MapLayout {
        MapLayout::Layers
    }

    fn new_slot(&self) -> Result<SlotMaps> {
        let (rd, layers) = (self.desc.rd, self.desc.layers());
        let views = self.capacity as usize * self.desc.layout.views() as usize;
        let mut slot = SlotMaps::new(&self.pipeline, (rd, rd, self.capacity * layers), views)?;
        slot.framebuffers = (0..self.capacity)
            .map(|i| slot.layer_framebuffer(&self.pipeline, (i * layers, layers), layers))
            .collect::<Result<_>>()?;
        Ok(slot)
    }

    fn record(&self, enc: &Encoder<'_>, slot: &mut SlotMaps, batch: &BatchViews, ck: CkParams) -> Result<()> {
        let layers = self.desc.layers();
        slot.write_views(batch, |i, layer| i * layers + layer)?;
        let per_sensor = batch.per_sensor as u32;
        // Sensor i: its own framebuffer, its views, gl_Layer relative to its first layer.
        for i in 0..batch.len() as u32 {
            let pass = self.pipeline.begin(enc, slot, &slot.framebuffers[i as usize], ck, None);
            let push = SensorPush { layer_base: i * layers, ..ck.push() };
            self.pipeline.draw_views(&pass, slot, &push, (i * per_sensor, per_sensor));
        }
        Ok(())
    }
}
