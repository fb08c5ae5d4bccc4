//! Interpolation pass (paper §III-G, docs/DESIGN.md §3 step 5): fills the quads the refinement accepted by
//! bilinear interpolation of their sensed corners. Shader: `glsl/interpolate.comp`, one workgroup per quad.
//! CPU twin: [`crate::sensors::refine::interpolate_cpu`].

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use crate::gpu_types::{GpuQuad, ImagePush};
use crate::scene::ImageSize;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, transfer};

/// Maps interpolated alike: the radiance map and its indirect part.
const MAPS: u32 = 2;

pub struct InterpolatePass {
    kernel: ComputeKernel,
    /// Holds the quads bound by the last [`InterpolatePass::bind`].
    quads: Option<Buffer>,
    count: u32,
}

impl InterpolatePass {
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let kernel = ComputeKernel::new(
            device,
            shaders::INTERPOLATE_COMP,
            &[(0, storage), (1, storage)],
            size_of::<ImagePush>() as u32,
            MAPS,
        )?;
        Ok(Self { kernel, quads: None, count: 0 })
    }

    /// Uploads `quads` and binds the maps they fill, the radiance map and its indirect part (call while the
    /// GPU is idle).
    pub fn bind(&mut self, device: &Arc<Device>, quads: &[GpuQuad], maps: [&Buffer; MAPS as usize]) -> Result<()> {
        let buffer = transfer::upload(device, "interpolated quads", quads, vk::BufferUsageFlags::STORAGE_BUFFER)?;
        for (set, map) in maps.into_iter().enumerate() {
            self.kernel.writer(set).storage_buffer(0, &buffer).storage_buffer(1, map).apply(device);
        }
        self.quads = Some(buffer);
        self.count = quads.len() as u32;
        Ok(())
    }

    pub fn record(&self, enc: &Encoder<'_>, size: ImageSize) {
        if self.count == 0 {
            return;
        }
        // Workgroups beyond the per-dimension limit spill into y; the shader skips indices past `count`.
        let max_x = enc.device().adapter.limits.max_compute_work_group_count[0];
        let groups = [self.count.min(max_x), self.count.div_ceil(max_x), 1];
        let push = ImagePush { width: size.width, height: size.height, radius: 0, count: self.count };
        for set in 0..MAPS as usize {
            self.kernel.dispatch(enc, set, &push, groups);
        }
    }
}
