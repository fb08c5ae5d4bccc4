//! A swapchain: the window's images, each acquired, drawn into by one submission and presented in turn.
//!
//! ```text
//!   acquire ──(acquired)──► submission: waits at its transfer stage, draws ──(ready[i])──► present
//! ```
//!
//! One image is drawn at a time (its owner waits for the previous submission before it acquires again), so
//! one `acquired` semaphore serves every image; `ready` is one per image, reused only once the
//! presentation engine has given that image back.

use std::sync::Arc;

use anyhow::{Context as _, Result, bail, ensure};
use ash::vk;

use super::device::Device;

/// The formats a picture is shown in: 8-bit and UNORM, so the bytes written are the bytes shown (a PNG's,
/// already sRGB-encoded), in this order of preference.
pub const FORMATS: [vk::Format; 2] = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM];

pub struct Swapchain {
    device: Arc<Device>,
    loader: ash::khr::swapchain::Device,
    raw: vk::SwapchainKHR,
    /// One of [`FORMATS`].
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    images: Vec<vk::Image>,
    acquired: vk::Semaphore,
    ready: Vec<vk::Semaphore>,
}

/// A swapchain image acquired for drawing.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub index: u32,
    pub image: vk::Image,
    /// Signalled when the image is ours: the submission that draws waits for it.
    pub acquired: vk::Semaphore,
    /// To be signalled by that submission: the presentation waits for it.
    pub ready: vk::Semaphore,
}

impl Swapchain {
    /// A swapchain on the device's window surface of `wanted` pixels (or the size the surface insists on).
    /// Its images are transfer destinations.
    pub fn new(device: &Arc<Device>, wanted: vk::Extent2D) -> Result<Self> {
        Self::create(device, wanted, vk::SwapchainKHR::null())
    }

    /// Makes this swapchain anew for `wanted` pixels (the window was resized, or it was out of date).
    pub fn recreate(&mut self, wanted: vk::Extent2D) -> Result<()> {
        // The old one's last presentation may still wait for a `ready` semaphore that dropping it destroys.
        self.device.wait_idle()?;
        let new = Self::create(&self.device, wanted, self.raw)?;
        drop(std::mem::replace(self, new));
        Ok(())
    }

    /// A swapchain retiring `old` (null for none).
    fn create(device: &Arc<Device>, wanted: vk::Extent2D, old: vk::SwapchainKHR) -> Result<Self> {
        let surface = device.surface().context("the device was not opened for a window")?;
        let adapter = device.adapter.handle;
        // SAFETY: queries on the device's own physical device and surface.
        let (caps, formats, modes) = unsafe {
            let s = &surface.loader;
            (
                s.get_physical_device_surface_capabilities(adapter, surface.raw)?,
                s.get_physical_device_surface_formats(adapter, surface.raw)?,
                s.get_physical_device_surface_present_modes(adapter, surface.raw)?,
            )
        };
        let instance = &device.instance().raw;
        let blits = |format: vk::Format| {
            // SAFETY: a query on a valid physical device.
            let features = unsafe { instance.get_physical_device_format_properties(adapter, format) };
            features
                .optimal_tiling_features
                .contains(vk::FormatFeatureFlags::BLIT_SRC | vk::FormatFeatureFlags::BLIT_DST)
        };
        let Some(format) = FORMATS.into_iter().find(|&f| {
            blits(f) && formats.iter().any(|s| s.format == f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
        }) else {
            let offered: Vec<String> = formats.iter().map(|f| format!("{:?}", f.format)).collect();
            bail!("the window offers no 8-bit UNORM format to copy pictures into (it offers {})", offered.join(", "));
        };
        ensure!(
            caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_DST),
            "the window's images cannot be copied into (no TRANSFER_DST usage)"
        );
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: wanted.width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: wanted.height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        let count = match caps.max_image_count {
            0 => caps.min_image_count + 1,
            max => (caps.min_image_count + 1).min(max),
        };
        // Mailbox never blocks the renderer on the display's refresh; FIFO is always there.
        let mode = [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::FIFO]
            .into_iter()
            .find(|m| modes.contains(m))
            .unwrap_or(vk::PresentModeKHR::FIFO);
        let alpha = [vk::CompositeAlphaFlagsKHR::OPAQUE, vk::CompositeAlphaFlagsKHR::INHERIT]
            .into_iter()
            .find(|&a| caps.supported_composite_alpha.contains(a))
            .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let loader = {
            let _loader = super::instance::loader_lock();
            ash::khr::swapchain::Device::new(instance, &device.raw)
        };
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(count)
            .image_format(format)
            .image_color_space(vk::ColorSpaceKHR::SRGB_NONLINEAR)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(alpha)
            .present_mode(mode)
            .clipped(true)
            .old_swapchain(old);
        // SAFETY: the surface outlives the swapchain (the device owns it); `old` is retired by this call.
        let raw = unsafe { loader.create_swapchain(&info, None) }.context("vkCreateSwapchainKHR")?;
        let mut chain = Self {
            device: device.clone(),
            loader,
            raw,
            format,
            extent,
            images: Vec::new(),
            acquired: vk::Semaphore::null(),
            ready: Vec::new(),
        };
        // Filled in after `chain` owns the swapchain, so an error here destroys what was made.
        // SAFETY: queries and creations on valid objects; `Drop` destroys them.
        unsafe {
            chain.images = chain.loader.get_swapchain_images(raw)?;
            let semaphore = || device.raw.create_semaphore(&vk::SemaphoreCreateInfo::default(), None);
            chain.acquired = semaphore()?;
            for _ in 0..chain.images.len() {
                chain.ready.push(semaphore()?);
            }
        }
        Ok(chain)
    }

    /// The next image to draw, or `None` when the swapchain no longer matches its window (make a new one).
    /// The previous frame's submission must have completed (it waited for the same `acquired` semaphore).
    pub fn acquire(&self) -> Result<Option<Frame>> {
        // SAFETY: valid swapchain and semaphore; the semaphore is unsignalled (see above).
        match unsafe { self.loader.acquire_next_image(self.raw, u64::MAX, self.acquired, vk::Fence::null()) } {
            Ok((index, _suboptimal)) => Ok(Some(Frame {
                index,
                image: self.images[index as usize],
                acquired: self.acquired,
                ready: self.ready[index as usize],
            })),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(None),
            Err(e) => Err(e).context("vkAcquireNextImageKHR"),
        }
    }

    /// Presents `frame` once its `ready` semaphore is signalled. `false`: the swapchain no longer matches
    /// its window (out of date or suboptimal): make a new one before the next frame.
    pub fn present(&self, frame: Frame) -> Result<bool> {
        let (chains, indices, waits) = ([self.raw], [frame.index], [frame.ready]);
        let info = vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&chains).image_indices(&indices);
        let queue = self.device.queue();
        // SAFETY: the queue is used under its mutex; the image was acquired and its drawing submitted.
        match unsafe { self.loader.queue_present(*queue, &info) } {
            Ok(suboptimal) => Ok(!suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(e) => Err(e).context("vkQueuePresentKHR"),
        }
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        // Presentations still waiting for a `ready` semaphore end once the queue is idle.
        let _ = self.device.wait_idle();
        // SAFETY: idle (above); the images belong to the swapchain and go with it.
        unsafe {
            for &s in self.ready.iter().chain([&self.acquired]) {
                self.device.raw.destroy_semaphore(s, None);
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}
