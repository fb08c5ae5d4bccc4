//! The radiance cache's transport rows (docs/DESIGN.md §10): after a batch's maps were drawn with
//! `CacheRead::Entries`, copies which cache value each texel of each sensor's main layers sees into the
//! batch's texel list (`u32` per texel, `gpu_types::TRANSPORT_NONE` where it sees no surface), which the host
//! weighs and sums into the sensor's row (`gi::transport`). Shader: `glsl/transport.comp`, one workgroup per
//! sensor.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use super::sensor_maps::{MapLayout, StrategyDesc};
use crate::gpu_types::TransportPush;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, Image};

pub struct TransportPass {
    kernel: ComputeKernel,
    push: TransportPush,
}

impl TransportPass {
    /// For sensors described by `desc`, with one descriptor set for each of `slots` batches in flight.
    pub fn new(device: &Arc<Device>, desc: &StrategyDesc, slots: u32) -> Result<Self> {
        let bindings = [(0, vk::DescriptorType::STORAGE_IMAGE), (1, vk::DescriptorType::STORAGE_BUFFER)];
        let kernel =
            ComputeKernel::new(device, shaders::TRANSPORT_COMP, &bindings, size_of::<TransportPush>() as u32, slots)?;
        let push = TransportPush {
            rd: desc.rd,
            layers: desc.layout.layers(),
            main_layers: desc.layout.main_layers(),
            atlas_columns: 0,
        };
        Ok(Self { kernel, push })
    }

    /// Texels a sensor's list holds: its main layers'.
    pub fn texels_per_sensor(&self) -> usize {
        (self.push.main_layers * self.push.rd * self.push.rd) as usize
    }

    /// Binds slot `slot`'s maps and texel list (call while that slot's work is not in flight).
    pub fn bind(&self, device: &Device, slot: usize, maps: &Image, texels: &Buffer) {
        self.kernel.writer(slot).storage_image(0, maps.view).storage_buffer(1, texels).apply(device);
    }

    /// Records the copy of the first `count` sensors of slot `slot`'s batch, whose maps lie as `layout`.
    pub fn record(&self, enc: &Encoder<'_>, slot: usize, layout: MapLayout, count: u32) {
        let atlas_columns = match layout {
            MapLayout::Layers => 0,
            MapLayout::Atlas { columns } => columns,
        };
        self.kernel.dispatch(enc, slot, &TransportPush { atlas_columns, ..self.push }, [count, 1, 1]);
    }
}
