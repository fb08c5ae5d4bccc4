//! Composition (docs/DESIGN.md §3 step 7): `final = Le + albedo · R` from the G-buffer and R, where R is the
//! filtered radiance map with its indirect part filtered apart: `R = R_f − I_f + I_i`, `R_f` and `I_f` R and
//! its indirect part at R's filter radius and `I_i` the indirect part at its own. Also writes that R, the
//! radiance AOV. A pixel where no surface is seen (`NO_SURFACE` in the G-buffer) shows the background radiance
//! (under a sky map, the sky over its square, computed on the host) with alpha 0, a surface alpha 1: the image's alpha is its coverage. CPU twin: `reference::post::compose`.
//! Shader: `glsl/compose.comp`.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use glam::Vec3;

use crate::gpu_types::ComposePush;
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
            &[
                (0, storage),
                (1, storage),
                (2, image),
                (3, image),
                (4, storage),
                (5, storage),
                (6, storage),
                (7, image),
                (8, storage),
            ],
            size_of::<ComposePush>() as u32,
            1,
        )?;
        Ok(Self { kernel })
    }

    /// `r`: R at R's filter radius, its indirect part at that radius and at its own; `out`: the image and
    /// the R it was composed from; `sky`: each pixel's sky (`vec4`; read only when recorded with a sky).
    pub fn bind(&self, device: &Device, r: [&Buffer; 3], out: [&Buffer; 2], gbuffer: &GBuffer, sky: &Buffer) {
        self.kernel
            .writer(0)
            .storage_buffer(0, r[0])
            .storage_buffer(1, out[0])
            .storage_image(2, gbuffer.albedo.view)
            .storage_image(3, gbuffer.emission.view)
            .storage_buffer(4, r[1])
            .storage_buffer(5, r[2])
            .storage_buffer(6, out[1])
            .storage_image(7, gbuffer.surface.view)
            .storage_buffer(8, sky)
            .apply(device);
    }

    /// `apart`: whether the indirect part was filtered at a radius of its own (else R is taken as it is);
    /// `background`: what pixels without a surface show, `None` for the sky bound with them.
    pub fn record(&self, enc: &Encoder<'_>, size: ImageSize, apart: bool, background: Option<Vec3>) {
        let push = ComposePush {
            background: background.unwrap_or(Vec3::ZERO).extend(0.0).to_array(),
            width: size.width,
            height: size.height,
            apart: apart as u32,
            sky: background.is_none() as u32,
        };
        self.kernel.dispatch(enc, 0, &push, [groups_for(size.width, 8), groups_for(size.height, 8), 1]);
    }
}
