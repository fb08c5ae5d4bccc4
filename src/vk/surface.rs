//! A window's surface: what a swapchain presents to. The window itself belongs to the windowing library;
//! here only its handles, which must stay valid while the [`Device`](super::Device) that owns the surface
//! lives.

use std::ffi::c_char;

use anyhow::{Context as _, Result};
use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use super::instance::Instance;

/// The window a device presents to, by its raw handles (X11, Wayland, Win32, …).
#[derive(Clone, Copy, Debug)]
pub struct WindowTarget {
    pub display: RawDisplayHandle,
    pub window: RawWindowHandle,
}

impl WindowTarget {
    /// The instance extensions a surface on this display needs.
    pub fn instance_extensions(&self) -> Result<&'static [*const c_char]> {
        ash_window::enumerate_required_extensions(self.display)
            .context("this display's kind of window cannot be presented to by Vulkan")
    }
}

/// Owns a `VkSurfaceKHR`; destroyed before the instance it was made from (its owner, the device, drops it
/// first).
pub struct Surface {
    pub loader: ash::khr::surface::Instance,
    pub raw: vk::SurfaceKHR,
}

impl Surface {
    /// The surface of `target` on `instance`, which was created with [`WindowTarget::instance_extensions`].
    pub fn new(instance: &Instance, target: &WindowTarget) -> Result<Self> {
        // SAFETY: the handles are a live window's (the caller keeps it open while the device lives), and the
        // instance has the extensions the display needs.
        let raw =
            unsafe { ash_window::create_surface(&instance.entry, &instance.raw, target.display, target.window, None) }
                .context("cannot create a Vulkan surface for the window")?;
        Ok(Self { loader: ash::khr::surface::Instance::new(&instance.entry, &instance.raw), raw })
    }

    /// Whether queue `family` of `device` can present to this surface.
    pub fn supports(&self, device: vk::PhysicalDevice, family: u32) -> bool {
        // SAFETY: a query on a valid physical device and surface of the same instance.
        unsafe { self.loader.get_physical_device_surface_support(device, family, self.raw) }.unwrap_or(false)
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        // SAFETY: the swapchains made on it held the device, which is gone; the instance is still alive.
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}
