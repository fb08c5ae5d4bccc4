//! Showing a picture in the window: its texels copied into an image of the render's size, then blitted into
//! the swapchain's image, letterboxed (scaled to fit, aspect kept; 1:1 and nearest where the window is the
//! render's size, so the window shows the very bytes of the PNG).
//!
//! ```text
//!   texels ─► staging buffer ─copy─► picture (render's size) ─blit─► swapchain image ─► present
//!                                                        (grey bars where the window's aspect differs)
//! ```
//!
//! One submission at a time, in its own command slot: the next picture waits for the previous one's
//! fence, never for the sensor batches (which have their own slots and run meanwhile).

use std::sync::Arc;

use anyhow::{Result, ensure};
use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::scene::ImageSize;
use crate::vk::barrier::{self, Access};
use crate::vk::swapchain::Swapchain;
use crate::vk::{Buffer, CommandSlot, Device, Image, ImageDesc};

/// The letterbox bars' grey (UNORM bytes / 255).
const BARS: f32 = 0.12;

pub struct Presenter {
    // Field order is drop order: the slot waits for its submission before the rest goes.
    slot: CommandSlot,
    swapchain: Swapchain,
    /// The swapchain no longer matches the window: made anew before the next picture.
    stale: bool,
    picture: Image,
    staging: Buffer,
}

impl Presenter {
    /// A presenter of pictures of `size` in a window of `window` pixels (the device's surface).
    pub fn new(device: &Arc<Device>, size: ImageSize, window: (u32, u32)) -> Result<Self> {
        let swapchain = Swapchain::new(device, extent(window))?;
        // SAMPLED only because every image here has a view, which transfer usage alone does not allow.
        let usage =
            vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED;
        let picture = Image::new(
            device,
            "viewer picture",
            ImageDesc {
                format: swapchain.format,
                width: size.width,
                height: size.height,
                layers: 1,
                usage,
                view_type: vk::ImageViewType::TYPE_2D,
            },
        )?;
        let bytes = 4 * size.width as u64 * size.height as u64;
        let staging =
            Buffer::new(device, "viewer texels", bytes, vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu)?;
        Ok(Self { slot: CommandSlot::new(device)?, swapchain, stale: false, picture, staging })
    }

    /// The texel format [`Presenter::show`] takes (`display::texels`).
    pub fn format(&self) -> vk::Format {
        self.swapchain.format
    }

    /// Shows `texels` (the picture's size, in [`Presenter::format`]) in a window of `window` pixels now.
    /// Does nothing while the window has no area (minimised).
    pub fn show(&mut self, texels: &[u8], window: (u32, u32)) -> Result<()> {
        let d = self.picture.desc;
        ensure!(texels.len() == 4 * d.width as usize * d.height as usize, "a picture of the wrong size");
        if window.0 == 0 || window.1 == 0 {
            return Ok(());
        }
        // The previous picture's copy is done with the staging buffer and the `acquired` semaphore.
        self.slot.wait()?;
        // Out of date twice running: the window is changing size; the next picture will find it settled.
        let mut frame = None;
        for _ in 0..2 {
            if self.stale || self.swapchain.extent != extent(window) {
                self.swapchain.recreate(extent(window))?;
                self.stale = false;
            }
            frame = self.swapchain.acquire()?;
            self.stale = frame.is_none();
            if frame.is_some() {
                break;
            }
        }
        let Some(frame) = frame else { return Ok(()) };
        self.staging.write(0, texels)?;
        let (picture, staging, target) = (&self.picture, &self.staging, self.swapchain.extent);
        self.slot.record(|enc| {
            let raw = &enc.device().raw;
            let range = picture.full_range();
            let (dst, src) = (vk::ImageLayout::TRANSFER_DST_OPTIMAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
            barrier::image(
                enc,
                picture,
                range,
                (&[Access::Nothing], vk::ImageLayout::UNDEFINED),
                (&[Access::TransferWrite], dst),
            );
            let layers = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
            let copy = vk::BufferImageCopy::default().image_subresource(layers).image_extent(vk::Extent3D {
                width: d.width,
                height: d.height,
                depth: 1,
            });
            // SAFETY: recording; the picture is a transfer destination; the buffer holds its texels.
            unsafe { raw.cmd_copy_buffer_to_image(enc.raw(), staging.raw, picture.raw, dst, &[copy]) };
            barrier::image(enc, picture, range, (&[Access::TransferWrite], dst), (&[Access::TransferRead], src));
            barrier::raw_image(
                enc,
                frame.image,
                range,
                (&[Access::Acquired], vk::ImageLayout::UNDEFINED),
                (&[Access::TransferWrite], dst),
            );
            let grey = vk::ClearColorValue { float32: [BARS, BARS, BARS, 1.0] };
            let (offset, size) = letterbox((d.width, d.height), (target.width, target.height));
            let filter = if size == (d.width, d.height) { vk::Filter::NEAREST } else { vk::Filter::LINEAR };
            let corner = |x: u32, y: u32| vk::Offset3D { x: x as i32, y: y as i32, z: 1 };
            let blit = vk::ImageBlit::default()
                .src_subresource(layers)
                .src_offsets([vk::Offset3D::default(), corner(d.width, d.height)])
                .dst_subresource(layers)
                .dst_offsets([
                    vk::Offset3D { x: offset.0 as i32, y: offset.1 as i32, z: 0 },
                    corner(offset.0 + size.0, offset.1 + size.1),
                ]);
            // SAFETY: recording; both images are in the layouts the barriers left them in.
            unsafe {
                raw.cmd_clear_color_image(enc.raw(), frame.image, dst, &grey, &[range]);
                barrier::raw_image(
                    enc,
                    frame.image,
                    range,
                    (&[Access::TransferWrite], dst),
                    (&[Access::TransferWrite], dst),
                );
                raw.cmd_blit_image(enc.raw(), picture.raw, src, frame.image, dst, &[blit], filter);
            }
            let present = vk::ImageLayout::PRESENT_SRC_KHR;
            barrier::raw_image(enc, frame.image, range, (&[Access::TransferWrite], dst), (&[Access::Present], present));
            Ok(())
        })?;
        self.slot.submit_between((frame.acquired, vk::PipelineStageFlags::TRANSFER), frame.ready)?;
        self.stale = !self.swapchain.present(frame)?;
        Ok(())
    }
}

fn extent((width, height): (u32, u32)) -> vk::Extent2D {
    vk::Extent2D { width, height }
}

/// Where a picture of `size` goes in a window of `window`: the largest rectangle of its aspect that fits,
/// centred (offset, size), at least a pixel.
fn letterbox(size: (u32, u32), window: (u32, u32)) -> ((u32, u32), (u32, u32)) {
    let scale = (window.0 as f64 / size.0 as f64).min(window.1 as f64 / size.1 as f64);
    let fit = |n: u32, limit: u32| ((n as f64 * scale).round() as u32).clamp(1, limit);
    let (w, h) = (fit(size.0, window.0), fit(size.1, window.1));
    (((window.0 - w) / 2, (window.1 - h) / 2), (w, h))
}

#[cfg(test)]
mod tests {
    use super::letterbox;

    #[test]
    fn a_picture_fills_a_window_of_its_size_and_keeps_its_aspect_in_others() {
        assert_eq!(letterbox((256, 256), (256, 256)), ((0, 0), (256, 256)));
        assert_eq!(letterbox((256, 256), (512, 300)), ((106, 0), (300, 300)));
        assert_eq!(letterbox((400, 200), (200, 200)), ((0, 50), (200, 100)));
        assert_eq!(letterbox((1000, 1), (10, 10)), ((0, 4), (10, 1)), "never thinner than a pixel");
    }
}
