//! Reduction pass (docs/DESIGN.md §3 step 4): each sensor's layers → `R = (1/π) Σ Ck·w` at the sensor's pixel of
//! the radiance map, and in the batch's results. Shader: `glsl/reduce.comp` (one workgroup per sensor, tree
//! reduction in shared memory). One descriptor set per batch in flight, each bound to that batch's maps,
//! pixel list and results.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use super::sensor_maps::MapLayout;
use crate::gpu_types::ReducePush;
use crate::sensors::{SensorKind, weights};
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, Image, transfer};

pub struct ReducePass {
    kernel: ComputeKernel,
    /// f32 weight per texel of one sensor's layers ([layer][row][col]).
    weights: Buffer,
    rd: u32,
    layers: u32,
}

/// What one batch's reduction reads and writes.
pub struct ReduceBindings<'a> {
    /// The batch's sensor maps.
    pub maps: &'a Image,
    /// Radiance-map pixel of each sensor of the batch (u32).
    pub pixels: &'a Buffer,
    /// R of each sensor of the batch (vec4), for the host.
    pub results: &'a Buffer,
    /// The radiance map of the current render.
    pub radiance: &'a Buffer,
}

impl ReducePass {
    /// For sensors of `kind` and size `rd`, with one descriptor set for each of `slots` batches in flight.
    pub fn new(device: &Arc<Device>, kind: SensorKind, rd: u32, slots: u32) -> Result<Self> {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let kernel = ComputeKernel::new(
            device,
            shaders::REDUCE_COMP,
            &[(0, vk::DescriptorType::STORAGE_IMAGE), (1, storage), (2, storage), (3, storage), (4, storage)],
            size_of::<ReducePush>() as u32,
            slots,
        )?;
        let w: Vec<f32> = weights::sensor_weights(kind, rd).into_iter().map(|w| w as f32).collect();
        let weights = transfer::upload(device, "texel weights", &w, vk::BufferUsageFlags::STORAGE_BUFFER)?;
        Ok(Self { kernel, weights, rd, layers: kind.layers() })
    }

    /// Binds slot `slot`'s resources (call while that slot's work is not in flight).
    pub fn bind(&self, device: &Device, slot: usize, b: &ReduceBindings<'_>) {
        self.kernel
            .writer(slot)
            .storage_image(0, b.maps.view)
            .storage_buffer(1, &self.weights)
            .storage_buffer(2, b.pixels)
            .storage_buffer(3, b.radiance)
            .storage_buffer(4, b.results)
            .apply(device);
    }

    /// Records the reduction of the first `count` sensors of slot `slot`'s batch, whose maps lie as `layout`.
    pub fn record(&self, enc: &Encoder<'_>, slot: usize, layout: MapLayout, count: u32) {
        let atlas_columns = match layout {
            MapLayout::Layers => 0,
            MapLayout::Atlas { columns } => columns,
        };
        let push = ReducePush { rd: self.rd, layers: self.layers, atlas_columns, _pad: 0 };
        self.kernel.dispatch(enc, slot, &push, [count, 1, 1]);
    }
}
