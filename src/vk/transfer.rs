//! Copies between the GPU and the host: the read-backs every test and output writer uses.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;

use super::barrier::{self, Access};
use super::buffer::Buffer;
use super::device::Device;
use super::image::Image;

/// Bytes per texel of the formats this program reads back.
pub fn texel_bytes(format: vk::Format) -> Result<usize> {
    Ok(match format {
        vk::Format::R32_UINT | vk::Format::R32_SFLOAT => 4,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => 16,
        other => anyhow::bail!("no read-back for format {other:?}"),
    })
}

/// A copy of every layer of `image` to or from a tightly packed buffer.
fn whole_image(image: &Image) -> vk::BufferImageCopy {
    let d = image.desc;
    vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: image.range(0, 1).aspect_mask,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: d.layers,
        })
        .image_extent(vk::Extent3D { width: d.width, height: d.height, depth: 1 })
}

/// A device-local buffer holding `data`, filled through a staging buffer.
pub fn upload<T: bytemuck::Pod>(
    device: &Arc<Device>,
    name: &str,
    data: &[T],
    usage: vk::BufferUsageFlags,
) -> Result<Buffer> {
    let usage = usage | vk::BufferUsageFlags::TRANSFER_DST;
    let buffer = Buffer::new(device, name, size_of_val(data) as u64, usage, MemoryLocation::GpuOnly)?;
    write_buffer(device, &buffer, data)?;
    Ok(buffer)
}

/// Fills the start of a device buffer with `data` through a staging buffer (waits).
pub fn write_buffer<T: bytemuck::Pod>(device: &Arc<Device>, buffer: &Buffer, data: &[T]) -> Result<()> {
    let bytes = size_of_val(data) as u64;
    anyhow::ensure!(bytes <= buffer.size, "write_buffer: {bytes} bytes into a buffer of {}", buffer.size);
    if bytes == 0 {
        return Ok(());
    }
    let mut staging =
        Buffer::new(device, "staging", bytes, vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu)?;
    staging.write(0, data)?;
    device.submit_and_wait(|enc| {
        enc.copy(&staging, buffer, bytes);
        Ok(())
    })?;
    Ok(())
}

/// Copies every layer of `image` (in `GENERAL` layout, its writers finished) to the host, layer-major, rows
/// top to bottom, as `T` (e.g. `[f32; 4]` for RGBA32F, `u32` for R32_UINT, `[u16; 4]` for RGBA16F).
pub fn read_image<T: bytemuck::Pod>(device: &Arc<Device>, image: &Image) -> Result<Vec<T>> {
    let d = image.desc;
    let texel = texel_bytes(d.format)?;
    anyhow::ensure!(
        texel == size_of::<T>(),
        "read_image: {:?} texels are {texel} bytes, not {}",
        d.format,
        size_of::<T>()
    );
    let count = d.width as usize * d.height as usize * d.layers as usize;
    let staging = Buffer::new(
        device,
        "image read-back",
        (count * texel) as u64,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )?;
    device.submit_and_wait(|enc| {
        let range = image.full_range();
        let region = [whole_image(image)];
        let (general, source) = (vk::ImageLayout::GENERAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
        // Every pass leaves its images in GENERAL; copies read best from TRANSFER_SRC_OPTIMAL.
        barrier::image(enc, image, range, (&[Access::Any], general), (&[Access::TransferRead], source));
        // SAFETY: the image is in TRANSFER_SRC_OPTIMAL now; the buffer is large enough.
        unsafe { device.raw.cmd_copy_image_to_buffer(enc.raw(), image.raw, source, staging.raw, &region) };
        barrier::image(enc, image, range, (&[Access::TransferRead], source), (&[Access::Any], general));
        barrier::global(enc, &[Access::TransferWrite], &[Access::HostRead]);
        Ok(())
    })?;
    staging.read(count)
}

/// Copies the first `count` elements of a device buffer to the host.
pub fn read_buffer<T: bytemuck::Pod>(device: &Arc<Device>, buffer: &Buffer, count: usize) -> Result<Vec<T>> {
    let bytes = (count * size_of::<T>()) as u64;
    anyhow::ensure!(bytes <= buffer.size, "read_buffer: {bytes} bytes from a buffer of {}", buffer.size);
    let staging =
        Buffer::new(device, "buffer read-back", bytes, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?;
    if bytes > 0 {
        device.submit_and_wait(|enc| {
            // Writes of earlier submissions (e.g. compute passes) become visible to this copy.
            barrier::global(enc, &[Access::Any], &[Access::TransferRead]);
            enc.copy(buffer, &staging, bytes);
            barrier::global(enc, &[Access::TransferWrite], &[Access::HostRead]);
            Ok(())
        })?;
    }
    staging.read(count)
}

/// Fills every layer of `image` with `data` (layer-major, rows top to bottom) and leaves it in `GENERAL`.
pub fn write_image<T: bytemuck::Pod>(device: &Arc<Device>, image: &Image, data: &[T]) -> Result<()> {
    let d = image.desc;
    let count = d.width as usize * d.height as usize * d.layers as usize;
    anyhow::ensure!(data.len() == count && texel_bytes(d.format)? == size_of::<T>(), "write_image: wrong data size");
    let mut staging = Buffer::new(
        device,
        "image upload",
        size_of_val(data) as u64,
        vk::BufferUsageFlags::TRANSFER_SRC,
        MemoryLocation::CpuToGpu,
    )?;
    staging.write(0, data)?;
    device.submit_and_wait(|enc| {
        let range = image.full_range();
        let region = [whole_image(image)];
        let target = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
        barrier::image(
            enc,
            image,
            range,
            (&[Access::Any], vk::ImageLayout::UNDEFINED),
            (&[Access::TransferWrite], target),
        );
        // SAFETY: the image is in TRANSFER_DST_OPTIMAL; the buffer holds exactly the image's texels.
        unsafe { device.raw.cmd_copy_buffer_to_image(enc.raw(), staging.raw, image.raw, target, &region) };
        barrier::image(
            enc,
            image,
            range,
            (&[Access::TransferWrite], target),
            (&[Access::Any], vk::ImageLayout::GENERAL),
        );
        Ok(())
    })?;
    Ok(())
}
