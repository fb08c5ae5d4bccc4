//! Compute strategy: the batch's maps rasterized by a compute shader, one workgroup per map layer
//! (`glsl/sensor_compute.comp`, whose header draws the work), into the same 2D-array image as `layered`.
//!
//! ```text
//!   maps (2D array, rd × rd per layer):  | s0 L0 | s0 L1 | s0 L2 | s1 L0 | … |   one workgroup per layer
//!   a workgroup: tiles of ≤ 32² texels × (the layer's views × chunks of 128 triangles: set-up, raster) → shade
//! ```
//!
//! Why: at small maps the graphics strategies pay per view for a render pass's worth of fixed work (the
//! rasterizer's binning, viewports, draw set-up), not for texels; a workgroup per layer pays for its
//! triangles and texels only, and a compute-only chip (a data-centre GPU's graphics units are a sliver of
//! it) runs it on every core. It reads the same views, vertices, draw lists (from the culling pass) and
//! shading (`glsl/sensor_shade.glsl`) as the graphics strategies. Its coverage is computed in floating point
//! rather than the hardware's snapped fixed point, so it is not bit-identical to `per-sensor` (an edge
//! within 1/512 of a texel centre may fall the other way): it passes the self-check's tolerance and runs
//! when named; `auto` takes only bit-identical strategies, so never this one (`strategy::choose`).
//!
//! Measured on lavapipe it loses to `layered` (docs/BENCHMARKS.md "Compute rasterization"): llvmpipe runs a
//! workgroup's invocations 8 to a vector, so every triangle's span set-up is paid per invocation, where its
//! own rasterizer bins triangles and fills 4 × 4 blocks in hand-written SIMD.

use std::sync::Arc;

use anyhow::{Result, ensure};
use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{CkParams, MapLayout, SensorInputs, SlotMaps, Strategy, StrategyDesc};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::SensorComputePush;
use crate::sensors::views::BatchViews;
use crate::shaders;
use crate::strategy::StrategyKind;
use crate::vk::{Access, Buffer, DescriptorPool, Device, Encoder, Pipeline, PipelineLayout, barrier, compute};

/// Shared memory the shader's workgroup uses (`glsl/sensor_compute.comp`: 128 triangles' set-up, its
/// `vec3`s padded to 16 bytes as drivers may, and their spans in the 32 rows of a tile).
pub const SHARED_BYTES: u32 = 128 * (48 + 16 + 16 + 16 + 32 * 4);

/// Bindings of the shader: 0–7 as every sensor shader (`SlotMaps::input_writer`), then the vertices,
/// the clusters' indices, the draw lists and their counts, and the maps as a storage image.
const BINDINGS: u32 = 13;

pub struct Compute {
    // Field order is drop order.
    pipeline: Pipeline,
    layout: PipelineLayout,
    inputs: SensorInputs,
    /// Bound at bindings 9–11 where the maps are drawn at full detail (a binding must name a buffer).
    placeholder: Buffer,
    desc: StrategyDesc,
    capacity: u32,
}

impl Compute {
    pub fn new(device: &Arc<Device>, scene: &GpuScene, desc: StrategyDesc) -> Result<Self> {
        // Its shader reads each view's cluster list only, not the triangle pass's regions.
        let inputs = SensorInputs::new(device, scene, &StrategyDesc { cull_triangles: false, ..desc }, true);
        let stage = vk::ShaderStageFlags::COMPUTE;
        let bindings: Vec<_> = (0..BINDINGS)
            .map(|b| {
                let ty = if b == BINDINGS - 1 {
                    vk::DescriptorType::STORAGE_IMAGE
                } else {
                    vk::DescriptorType::STORAGE_BUFFER
                };
                (b, ty, stage)
            })
            .collect();
        let layout = PipelineLayout::new(device, &bindings, size_of::<SensorComputePush>() as u32, stage)?;
        let spirv = if scene.textured { shaders::SENSOR_COMPUTE_COMP_TEXTURES } else { shaders::SENSOR_COMPUTE_COMP };
        let pipeline = Pipeline::compute(device, &layout, spirv)?;
        let limits = &device.adapter.limits;
        let by_layers = limits.max_image_array_layers / desc.layers();
        ensure!(by_layers >= 1, "this device's images cannot hold {} layers", desc.layers());
        let capacity = by_layers.min(desc.batch_limit(device, inputs.draw_bytes(&desc))?);
        let placeholder = Buffer::new(
            device,
            "compute strategy placeholder",
            16,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self { pipeline, layout, inputs, placeholder, desc, capacity })
    }
}

impl Strategy for Compute {
    fn kind(&self) -> StrategyKind {
        StrategyKind::Compute
    }

    fn capacity(&self) -> u32 {
        self.capacity
    }

    fn map_layout(&self) -> MapLayout {
        MapLayout::Layers
    }

    fn new_slot(&self) -> Result<SlotMaps> {
        let device = &self.inputs.device;
        let (rd, layers) = (self.desc.rd, self.capacity * self.desc.layers());
        let views = self.capacity as usize * self.desc.layout.views() as usize;
        let pool = DescriptorPool::new(
            device,
            1,
            &[(vk::DescriptorType::STORAGE_BUFFER, BINDINGS - 1), (vk::DescriptorType::STORAGE_IMAGE, 1)],
        )?;
        let set = pool.allocate(&self.layout)?;
        let slot = SlotMaps::with_set(&self.inputs, (rd, rd, layers), views, (set, pool))?;
        let culled = self.inputs.culled.as_ref().zip(slot.draws.as_ref());
        let (vertices, indices, commands, counts) = match culled {
            Some((c, d)) => (&*c.vertices, &*c.indices, &d.commands, &d.counts),
            None => (&*self.inputs.vertices, &self.placeholder, &self.placeholder, &self.placeholder),
        };
        slot.input_writer(&self.inputs)
            .storage_buffer(8, vertices)
            .storage_buffer(9, indices)
            .storage_buffer(10, commands)
            .storage_buffer(11, counts)
            .storage_image(12, slot.maps.view)
            .apply(device);
        Ok(slot)
    }

    fn record(&self, enc: &Encoder<'_>, slot: &mut SlotMaps, batch: &BatchViews, ck: CkParams) -> Result<()> {
        let layers = self.desc.layers();
        slot.write_views(batch, |i, layer| i * layers + layer)?;
        let draws = slot.draws.as_ref();
        if draws.is_some() {
            // The culling pass wrote the draw lists for indirect draws; this shader reads them.
            barrier::global(enc, &[Access::ComputeWrite], &[Access::ComputeRead]);
        }
        let layer_count = batch.len() as u32 * layers;
        let push = SensorComputePush {
            clear: ck.background.clear_colour().into(),
            sensor: self.inputs.push(&ck.push()),
            rd: self.desc.rd,
            layers,
            per_sensor: batch.per_sensor as u32,
            layer_count,
            triangles: self.inputs.vertex_count / 3,
            max_per_view: draws.map_or(0, |d| d.max_per_view),
            culled: draws.is_some() as u32,
            count_buffer: draws.is_some_and(|d| d.count_buffer) as u32,
            _pad: [0; 2],
        };
        enc.bind(vk::PipelineBindPoint::COMPUTE, &self.pipeline, &self.layout, slot.set);
        enc.push(&self.layout, &push);
        enc.dispatch(compute::spilled(enc, layer_count));
        Ok(())
    }
}
