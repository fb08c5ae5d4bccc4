//! A render's targets: the G-buffer, the maps its sensors write, and the buffers the post passes fill, made
//! for the image's size and dropped when the render returns (all its work waited for).

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use glam::{Vec3, Vec4};
use gpu_allocator::MemoryLocation;

use super::Renderer;
use super::batch::SensedMaps;
use crate::gbuffer::GBufferData;
use crate::params::{Antialiasing, FrameParams};
use crate::passes::gbuffer::{self, GBuffer};
use crate::scene::ImageSize;
use crate::vk::{Buffer, Device, transfer};

/// What one render writes on the GPU; dropped when the render returns (all its work waited for).
pub(super) struct Targets {
    pub(super) gbuffer: GBuffer,
    /// R and its indirect part, shared with the batches in flight, which keep them alive until they complete.
    pub(super) sensed: SensedMaps,
    /// Which light points each pixel sees, 64 bits a pixel, for the filter (zeros without hints).
    pub(super) light_masks: Buffer,
    /// R filtered; its indirect part filtered at R's radius and at its own; what the image is composed from.
    pub(super) filtered: Buffer,
    pub(super) indirect_at_r: Buffer,
    pub(super) indirect_own: Buffer,
    pub(super) composed: Buffer,
    pub(super) image: Buffer,
    /// Under a sky map, the sky each pixel shows where no surface is (`vec4`; one unread texel without).
    pub(super) sky: Buffer,
}

impl Renderer {
    /// The G-buffer at `size`, on the GPU and on the host.
    pub(super) fn render_gbuffer(&self, size: ImageSize) -> Result<(GBuffer, GBufferData)> {
        let near = gbuffer::NEAR * self.scale;
        let gpu = self.gbuffer.render(&self.device, &self.scene, &self.camera, size, near)?;
        let host = gpu.read_back(&self.device)?;
        Ok((gpu, host))
    }

    /// The G-buffer at `size` (on the GPU and the host), the targets the render writes, cleared and bound to
    /// the sensors' runner; under a sky map, the sky each pixel shows where no surface is.
    pub(super) fn targets(
        &mut self,
        size: ImageSize,
        frame: &FrameParams,
    ) -> Result<(Targets, GBufferData, Option<Vec<Vec3>>)> {
        let device = self.device.clone();
        let pixels = size.width as usize * size.height as usize;
        let (gpu_gbuffer, g) = self.render_gbuffer(size)?;
        // Under a sky map, the sky each pixel shows where no surface is: over its square (64 points) or at
        // its centre, as the pixel is.
        let side = if frame.aa == Antialiasing::On { 8 } else { 1 };
        let sky = self.host.sky.as_ref().map(|sky| sky.pixels(&self.host.camera, size, side));
        let targets = Targets {
            gbuffer: gpu_gbuffer,
            sensed: SensedMaps::new(&device, size)?,
            light_masks: {
                let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
                Buffer::new(&device, "light masks", 8 * pixels as u64, usage, MemoryLocation::GpuOnly)?
            },
            filtered: map_buffer(&device, "filtered radiance map", size)?,
            indirect_at_r: map_buffer(&device, "indirect map at R's filter", size)?,
            indirect_own: map_buffer(&device, "indirect map, filtered", size)?,
            composed: map_buffer(&device, "composed radiance map", size)?,
            image: map_buffer(&device, "final image", size)?,
            sky: {
                let texels: Vec<Vec4> = match &sky {
                    Some(sky) => sky.iter().map(|s| s.extend(0.0)).collect(),
                    None => vec![Vec4::ZERO],
                };
                transfer::upload(&device, "sky pixels", &texels, vk::BufferUsageFlags::STORAGE_BUFFER)?
            },
        };
        device.submit_and_wait(|enc| {
            enc.fill(&targets.sensed.radiance, 0);
            enc.fill(&targets.sensed.indirect, 0);
            enc.fill(&targets.light_masks, 0);
            Ok(())
        })?;
        self.runner.bind(&targets.sensed)?;
        if let Some(fine) = &mut self.fine {
            fine.bind(&targets.sensed)?;
        }
        Ok((targets, g, sky))
    }
}

impl SensedMaps {
    /// Both maps for an image of `size`.
    pub(super) fn new(device: &Arc<Device>, size: ImageSize) -> Result<Self> {
        Ok(Self {
            radiance: Arc::new(map_buffer(device, "radiance map", size)?),
            indirect: Arc::new(map_buffer(device, "indirect map", size)?),
        })
    }
}

/// A radiance-map-sized buffer of `vec4` per pixel, written by compute passes and read back.
pub(super) fn map_buffer(device: &Arc<Device>, name: &str, size: ImageSize) -> Result<Buffer> {
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    Buffer::new(device, name, size.width as u64 * size.height as u64 * 16, usage, MemoryLocation::GpuOnly)
}
