//! A compute kernel: one shader, its descriptor set and pipeline. The compute passes are thin wrappers
//! that say what they bind and how many workgroups they launch.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use super::descriptor::{DescriptorPool, SetWriter};
use super::device::Device;
use super::pipeline::{Binding, Pipeline, PipelineLayout};

pub struct ComputeKernel {
    // Field order is drop order: pipeline, then its set's pool, then the layout.
    pipeline: Pipeline,
    _pool: DescriptorPool,
    pub set: vk::DescriptorSet,
    pub layout: PipelineLayout,
}

impl ComputeKernel {
    /// `bindings`: (binding, type) pairs, all for the compute stage; `push_bytes`: push-constant size.
    pub fn new(
        device: &Arc<Device>,
        spirv: &[u8],
        bindings: &[(u32, vk::DescriptorType)],
        push_bytes: u32,
    ) -> Result<Self> {
        let stage = vk::ShaderStageFlags::COMPUTE;
        let full: Vec<Binding> = bindings.iter().map(|&(b, ty)| (b, ty, stage)).collect();
        let layout = PipelineLayout::new(device, &full, push_bytes, stage)?;
        let mut per_type: Vec<(vk::DescriptorType, u32)> = Vec::new();
        for &(_, ty) in bindings {
            match per_type.iter_mut().find(|(t, _)| *t == ty) {
                Some((_, n)) => *n += 1,
                None => per_type.push((ty, 1)),
            }
        }
        let pool = DescriptorPool::new(device, 1, &per_type)?;
        let set = pool.allocate(&layout)?;
        let pipeline = Pipeline::compute(device, &layout, spirv)?;
        Ok(Self { pipeline, _pool: pool, set, layout })
    }

    /// Starts the writes to this kernel's descriptor set (apply them while the GPU is not using it).
    pub fn writer(&self) -> SetWriter {
        SetWriter::new(self.set)
    }

    /// Records bind, push constants and a dispatch of `groups` workgroups.
    pub fn dispatch<T: bytemuck::Pod>(&self, device: &Device, cmd: vk::CommandBuffer, push: &T, groups: [u32; 3]) {
        self.pipeline.bind(device, cmd, vk::PipelineBindPoint::COMPUTE, &self.layout, self.set);
        self.layout.push(cmd, push);
        // SAFETY: as above.
        unsafe { device.raw.cmd_dispatch(cmd, groups[0], groups[1], groups[2]) };
    }
}

/// Workgroups to cover `n` items with `size`-wide groups.
pub fn groups_for(n: u32, size: u32) -> u32 {
    n.div_ceil(size)
}
