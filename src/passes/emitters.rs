//! Emitter pass (docs/DESIGN.md §2, the exact estimator): each light group's unoccluded irradiance at each
//! sensor of a batch, in closed form, by chunks of at most `EMITTER_CHUNK` emitters (one invocation per
//! sensor and chunk). Shader: `glsl/emitters.comp` (with `glsl/polygon.glsl`, the twin of
//! `light::polygon`). The reduction sums a group's chunks and weighs them by the group's visibility.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use crate::gpu_scene::GpuScene;
use crate::gpu_types::EmitterPush;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, compute::spilled};

pub struct EmitterPass {
    kernel: ComputeKernel,
    emitters: Arc<Buffer>,
    chunks: Arc<Buffer>,
    chunk_count: u32,
    groups: u32,
}

/// What one batch's emitter pass reads and writes.
pub struct EmitterBindings<'a> {
    /// Each sensor's frame (`GpuSensor`) and zoom views (`GpuZoom`, `[sensor][group]`).
    pub sensors: &'a Buffer,
    pub zooms: &'a Buffer,
    /// `vec4` per sensor and chunk.
    pub irradiance: &'a Buffer,
}

impl EmitterPass {
    /// For `scene`'s emitters, with one descriptor set for each of `slots` batches in flight.
    pub fn new(device: &Arc<Device>, scene: &GpuScene, slots: u32) -> Result<Self> {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let bindings: Vec<_> = (0..5).map(|b| (b, storage)).collect();
        let kernel =
            ComputeKernel::new(device, shaders::EMITTERS_COMP, &bindings, size_of::<EmitterPush>() as u32, slots)?;
        Ok(Self {
            kernel,
            emitters: scene.emitters.clone(),
            chunks: scene.chunks.clone(),
            chunk_count: scene.chunk_count,
            groups: scene.lights.groups.len() as u32,
        })
    }

    /// Bytes of irradiance one sensor needs.
    pub fn bytes_per_sensor(&self) -> u64 {
        16 * self.chunk_count as u64
    }

    /// Binds slot `slot`'s resources (call while that slot's work is not in flight).
    pub fn bind(&self, device: &Device, slot: usize, b: &EmitterBindings<'_>) {
        self.kernel
            .writer(slot)
            .storage_buffer(0, b.sensors)
            .storage_buffer(1, b.zooms)
            .storage_buffer(2, &self.emitters)
            .storage_buffer(3, &self.chunks)
            .storage_buffer(4, b.irradiance)
            .apply(device);
    }

    /// Records the irradiance of every chunk at the first `sensors` sensors of slot `slot`'s batch.
    pub fn record(&self, enc: &Encoder<'_>, slot: usize, sensors: u32) {
        let invocations = sensors * self.chunk_count;
        if invocations == 0 {
            return;
        }
        // Workgroups beyond the per-dimension limit spill into y; the shader skips indices past the last.
        let push = EmitterPush { sensors, chunks: self.chunk_count, groups: self.groups, _pad: 0 };
        self.kernel.dispatch(enc, slot, &push, spilled(enc, invocations.div_ceil(64)));
    }
}
