//! Id-constrained Gaussian filter (paper §III-H, docs/DESIGN.md §3 step 6): a Gaussian of radius r, σ = r/2,
//! over the radiance map, taking only samples of the centre pixel's surface id and light mask (which points
//! on the lights it sees, `sensors::hints`), so that light does not bleed across a shadow's edge inside one
//! surface. Shader: `glsl/filter.comp`.
//! CPU twin: [`crate::reference::post::filter`].

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use crate::gpu_types::ImagePush;
use crate::scene::ImageSize;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, Image, compute::groups_for};

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
            1,
        )?;
        Ok(Self { kernel })
    }

    /// Filters `source` into `target` with the surface ids of the G-buffer and the pixels' light masks
    /// (64 bits each; all zero where there are none) (call while the GPU is idle).
    pub fn bind(&self, device: &Device, source: &Buffer, target: &Buffer, surface_ids: &Image, light_masks: &Buffer) {
        self.kernel
            .writer(0)
            .storage_buffer(0, source)
            .storage_buffer(1, target)
            .storage_image(2, surface_ids.view)
            .storage_buffer(3, light_masks)
            .apply(device);
    }

    /// Radius 0 copies the source unchanged.
    pub fn record(&self, enc: &Encoder<'_>, size: ImageSize, radius: u32) {
        let push = ImagePush { width: size.width, height: size.height, radius, count: 0 };
        self.kernel.dispatch(enc, 0, &push, [groups_for(size.width, 8), groups_for(size.height, 8), 1]);
    }
}
