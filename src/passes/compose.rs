//! Composition (docs/DESIGN.md §3 step 7): `final = Le + albedo · R` from the G-buffer and the filtered radiance
//! map. Shader: `glsl/compose.comp`.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use crate::gpu_types::ImagePush;
use crate::passes::gbuffer::GBuffer;
use crate::scene::ImageSize;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, compute::groups_for};

pub struct ComposePass {
    kernel: ComputeKernel,
}

impl ComposePass {
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let (storage, image) = (vk::DescriptorType::STORAGE_BUFFER, vk::DescriptorType::STORAGE_IMAGE);
        let kernel = ComputeKernel::new(
            device,
            shaders::COMPOSE_COMP,
            &[(0, storage), (1, storage), (2, image), (3, image)],
            size_of::<ImagePush>() as u32,
            1,
        )?;
        Ok(Self { kernel })
    }

    pub fn bind(&self, device: &Device, radiance: &Buffer, target: &Buffer, gbuffer: &GBuffer) {
        self.kernel
            .writer(0)
            .storage_buffer(0, radiance)
            .storage_buffer(1, target)
            .storage_image(2, gbuffer.albedo.view)
            .storage_image(3, gbuffer.emission.view)
            .apply(device);
    }

    pub fn record(&self, enc: &Encoder<'_>, size: ImageSize) {
        let push = ImagePush { width: size.width, height: size.height, radius: 0, count: 0 };
        self.kernel.dispatch(enc, 0, &push, [groups_for(size.width, 8), groups_for(size.height, 8), 1]);
    }
}
