//! Id-constrained Gaussian filter (paper §III-H, docs/DESIGN.md §3 step 6): a Gaussian of radius r, σ = r/2,
//! over a map of R, taking only samples of the centre pixel's surface id and light mask (which points on the
//! lights it sees, `sensors::hints`), so that light does not bleed across a shadow's edge inside one
//! surface. A render filters R and its indirect part apart, each at its own radius (`ComposePass` joins
//! them). Shader: `glsl/filter.comp`.
//! CPU twin: [`crate::reference::post::filter`].

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use crate::gpu_types::ImagePush;
use crate::scene::ImageSize;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, Image, compute::groups_for};

/// Filters a render runs: R at `--filter-radius`, its indirect part at the same radius (what R's filter did
/// to it) and at `--indirect-filter-radius` (what replaces that).
pub const FILTERS: usize = 3;

pub struct FilterPass {
    kernel: ComputeKernel,
}

impl FilterPass {
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let kernel = ComputeKernel::new(
            device,
            shaders::FILTER_COMP,
            &[(0, storage), (1, storage), (2, vk::DescriptorType::STORAGE_IMAGE), (3, storage)],
            size_of::<ImagePush>() as u32,
            FILTERS as u32,
        )?;
        Ok(Self { kernel })
    }

    /// Filter `set` (of [`FILTERS`]) filters `source` into `target` with the surface ids of the G-buffer and
    /// the pixels' light masks (64 bits each; all zero where there are none) (call while the GPU is idle).
    pub fn bind(
        &self,
        device: &Device,
        set: usize,
        (source, target): (&Buffer, &Buffer),
        surface_ids: &Image,
        light_masks: &Buffer,
    ) {
        self.kernel
            .writer(set)
            .storage_buffer(0, source)
            .storage_buffer(1, target)
            .storage_image(2, surface_ids.view)
            .storage_buffer(3, light_masks)
            .apply(device);
    }

    /// Records filter `set`; radius 0 copies the source unchanged.
    pub fn record(&self, enc: &Encoder<'_>, set: usize, size: ImageSize, radius: u32) {
        let push = ImagePush { width: size.width, height: size.height, radius, count: 0 };
        self.kernel.dispatch(enc, set, &push, [groups_for(size.width, 8), groups_for(size.height, 8), 1]);
    }
}
