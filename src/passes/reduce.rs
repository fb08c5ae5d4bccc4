//! Reduction pass (DESIGN.md §3 step 4): each sensor's layers → `R = (1/π) Σ Ck·w` at the sensor's pixel of
//! the radiance map. Shader: `glsl/reduce.comp` (one workgroup per sensor, tree reduction in shared memory).

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::gpu_types::ReducePush;
use crate::sensors::{SensorKind, weights};
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Image};

pub struct ReducePass {
    kernel: ComputeKernel,
    /// f32 weight per texel of one sensor's layers ([layer][row][col]).
    weights: Buffer,
    /// Radiance-map pixel of each sensor of the current batch (host-written).
    pixels: Buffer,
    rd: u32,
    layers: u32,
    /// Of the bound maps: 0 for array layers, else tiles per atlas row.
    atlas_columns: u32,
}

impl ReducePass {
    /// For sensors of `kind` and size `rd`, batches of up to `batch` sensors.
    pub fn new(device: &Arc<Device>, kind: SensorKind, rd: u32, batch: u32) -> Result<Self> {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let kernel = ComputeKernel::new(
            device,
            shaders::REDUCE_COMP,
            &[(0, vk::DescriptorType::STORAGE_IMAGE), (1, storage), (2, storage), (3, storage)],
            size_of::<ReducePush>() as u32,
        )?;
        let w: Vec<f32> = weights::sensor_weights(kind, rd).into_iter().map(|w| w as f32).collect();
        let weights = Buffer::upload(device, "texel weights", &w, vk::BufferUsageFlags::STORAGE_BUFFER)?;
        let pixels = Buffer::new(
            device,
            "sensor pixels",
            4 * batch as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        Ok(Self { kernel, weights, pixels, rd, layers: kind.layers(), atlas_columns: 0 })
    }

    /// Binds the sensor maps to read (`atlas_columns` as [`crate::passes::sensor_maps::Strategy::maps`]
    /// says) and the radiance map to write (call while the GPU is idle).
    pub fn bind(&mut self, device: &Device, maps: &Image, atlas_columns: u32, radiance: &Buffer) {
        self.atlas_columns = atlas_columns;
        self.kernel
            .writer()
            .storage_image(0, maps.view)
            .storage_buffer(1, &self.weights)
            .storage_buffer(2, &self.pixels)
            .storage_buffer(3, radiance)
            .apply(device);
    }

    /// Sets the pixels of the next batch's sensors (before recording; the previous batch must be finished).
    pub fn set_pixels(&mut self, pixels: &[u32]) -> Result<()> {
        self.pixels.write(0, pixels)
    }

    /// Records the reduction of the batch's sensors `first..first + count`.
    pub fn record(&self, device: &Device, cmd: vk::CommandBuffer, first: u32, count: u32) {
        let push =
            ReducePush { rd: self.rd, layers: self.layers, first_sensor: first, atlas_columns: self.atlas_columns };
        self.kernel.dispatch(device, cmd, &push, [count, 1, 1]);
    }
}
