//! A compute kernel: one shader, its pipeline, and descriptor sets for it. The compute passes are thin
//! wrappers that say what they bind and how many workgroups they launch.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use super::buffer::Buffer;
use super::descriptor::{DescriptorPool, SetWriter};
use super::device::Device;
use super::encoder::Encoder;
use super::pipeline::{Binding, Pipeline, PipelineLayout};

pub struct ComputeKernel {
    // Field order is drop order: pipeline, then its sets' pool, then the layout.
    pipeline: Pipeline,
    _pool: DescriptorPool,
    sets: Vec<vk::DescriptorSet>,
    layout: PipelineLayout,
}

impl ComputeKernel {
    /// `bindings`: (binding, type) pairs, all for the compute stage; `push_bytes`: push-constant size;
    /// `sets`: how many descriptor sets (e.g. one per batch in flight), addressed by index.
    pub fn new(
        device: &Arc<Device>,
        spirv: &[u8],
        bindings: &[(u32, vk::DescriptorType)],
        push_bytes: u32,
        sets: u32,
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
        let pool = DescriptorPool::new(device, sets, &per_type)?;
        let sets = (0..sets).map(|_| pool.allocate(&layout)).collect::<Result<Vec<_>>>()?;
        let pipeline = Pipeline::compute(device, &layout, spirv)?;
        Ok(Self { pipeline, _pool: pool, sets, layout })
    }

    /// Starts the writes to descriptor set `set` (apply them while the GPU is not using that set).
    pub fn writer(&self, set: usize) -> SetWriter {
        SetWriter::new(self.sets[set])
    }

    /// Records bind (with descriptor set `set`), push constants and a dispatch of `groups` workgroups.
    pub fn dispatch<T: bytemuck::Pod>(&self, enc: &Encoder<'_>, set: usize, push: &T, groups: [u32; 3]) {
        enc.bind(vk::PipelineBindPoint::COMPUTE, &self.pipeline, &self.layout, self.sets[set]);
        enc.push(&self.layout, push);
        enc.dispatch(groups);
    }

    /// Records bind, push constants and a dispatch of the workgroup counts at `offset` in `args`.
    pub fn dispatch_indirect<T: bytemuck::Pod>(
        &self,
        enc: &Encoder<'_>,
        set: usize,
        push: &T,
        (args, offset): (&Buffer, u64),
    ) {
        enc.bind(vk::PipelineBindPoint::COMPUTE, &self.pipeline, &self.layout, self.sets[set]);
        enc.push(&self.layout, push);
        enc.dispatch_indirect(args, offset);
    }
}

/// Workgroups to cover `n` items with `size`-wide groups.
pub fn groups_for(n: u32, size: u32) -> u32 {
    n.div_ceil(size)
}

/// `workgroups` laid out for a dispatch on `enc`'s device: along x up to its per-dimension limit, the rest
/// spilling into y (the shader flattens the two and skips indices past its count).
pub fn spilled(enc: &Encoder<'_>, workgroups: u32) -> [u32; 3] {
    let max_x = enc.device().adapter.limits.max_compute_work_group_count[0];
    [workgroups.min(max_x), workgroups.div_ceil(max_x), 1]
}
