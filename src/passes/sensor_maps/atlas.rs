//! Atlas strategy (ours): every sensor layer is an `rd × rd` tile of one large 2D image, each view drawn
//! with the viewport and scissor of its tile (`glsl/sensor_atlas.vert`).
//!
//! Why: a layered framebuffer is drawn layer after layer, and each layer is a separate small target; at
//! small rd a rasteriser that bins into fixed-size screen tiles (lavapipe's are 64 × 64) then works on
//! mostly empty tiles with per-layer overheads. One large target keeps every binning tile full and its
//! worker threads busy, and a smaller batch clears only the rows it uses.
//!
//! Why a viewport per tile rather than one instanced draw squeezing every view into its tile in clip space
//! (as this strategy first did): the squeeze rounds window coordinates differently from a layer of one's
//! own, and clips triangles at the tile's edges, so its maps, and the refinement decisions taken on them,
//! differed from the other strategies' (up to 6 % on a pixel of the shipped scenes). With the tile's
//! viewport every view is rasterized as in a layer of its own but for the tile's offset, whose window
//! coordinates round differently in their last bits: R differs from per-sensor's by 1e-4 relative RMSE on
//! the shipped scenes, not bit for bit, so `auto` never takes it (`tests/strategies.rs`,
//! `StrategyKind::rasterizes_like_per_sensor`).

use std::sync::Arc;

use anyhow::{Result, ensure};
use ash::vk;

use super::{CkParams, MapLayout, SensorPipeline, SlotMaps, Strategy, StrategyDesc};
use crate::gpu_scene::GpuScene;
use crate::sensors::views::BatchViews;
use crate::shaders;
use crate::strategy::StrategyKind;
use crate::vk::{Device, Encoder};

pub struct Atlas {
    pipeline: SensorPipeline,
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
        let pipeline = SensorPipeline::new(
            device,
            scene,
            &desc,
            ([shaders::SENSOR_ATLAS_VERT, shaders::SENSOR_ATLAS_VERT_TEXTURES], 0),
            true,
        )?;
        let capacity =
            (max_columns * max_rows / layers).min(desc.batch_limit(device, pipeline.draw_bytes(&desc))?).max(1);
        let tiles = capacity * layers;
        let columns = tiles.min(max_columns);
        let rows = tiles.div_ceil(columns);
        Ok(Self { pipeline, desc, columns, rows, capacity })
    }
}

impl Strategy for Atlas {
    fn kind(&self) -> StrategyKind {
        StrategyKind::Atlas
    }

    fn capacity(&self) -> u32 {
        self.capacity
    }

    fn map_layout(&self) -> MapLayout {
        MapLayout::Atlas { columns: self.columns }
    }

    fn new_slot(&self) -> Result<SlotMaps> {
        let size = (self.columns * self.desc.rd, self.rows * self.desc.rd, 1);
        let mut slot = SlotMaps::new(&self.pipeline, size, self.capacity as usize * self.desc.layout.views() as usize)?;
        slot.framebuffers = vec![slot.whole_framebuffer(&self.pipeline)?];
        Ok(slot)
    }

    fn record(&self, enc: &Encoder<'_>, slot: &mut SlotMaps, batch: &BatchViews, ck: CkParams) -> Result<()> {
        let layers = self.desc.layers();
        slot.write_views(batch, |i, layer| i * layers + layer)?;
        let count = batch.len() as u32;
        // Only the rows of tiles this batch uses are cleared and drawn.
        let rows_used = (count * layers).div_ceil(self.columns);
        let area = vk::Extent2D { width: self.columns * self.desc.rd, height: rows_used * self.desc.rd };
        let pass = self.pipeline.begin(enc, slot, &slot.framebuffers[0], ck, Some(area));
        let push = ck.push();
        let rd = self.desc.rd;
        for i in 0..count {
            for (j, view) in batch.of(i as usize).iter().enumerate() {
                let tile = i * layers + view.layer;
                let offset =
                    vk::Offset2D { x: ((tile % self.columns) * rd) as i32, y: ((tile / self.columns) * rd) as i32 };
                pass.set_viewport_scissor(vk::Rect2D { offset, extent: vk::Extent2D { width: rd, height: rd } });
                self.pipeline.draw_views(&pass, slot, &push, (i * batch.per_sensor as u32 + j as u32, 1));
            }
        }
        Ok(())
    }
}
