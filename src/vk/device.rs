//! The logical device: the one owner of the instance, the queue, the memory allocator and a command pool
//! for synchronous submissions. Every other Vulkan object holds an `Arc<Device>` and destroys itself first.

use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

use anyhow::{Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::adapter::{self, Adapter, Requirements};
use super::instance::{Instance, loader_lock};
use super::surface::{Surface, WindowTarget};
use super::validation::ValidationLog;

/// How to open a device.
#[derive(Clone, Debug, Default)]
pub struct DeviceOptions {
    /// Enable the Khronos validation layer and record its messages.
    pub validation: bool,
    /// Index from `sensorlight devices`; `None` picks the best supported device.
    pub device_index: Option<usize>,
    /// What the program's passes need; devices lacking any of it are skipped with the reason.
    pub requirements: Requirements,
    /// A window to present to (the live viewer): the device then owns its surface, enables swapchains, and
    /// only devices whose queue can present to it are chosen.
    pub window: Option<WindowTarget>,
}

impl DeviceOptions {
    /// Validation from `SENSORLIGHT_VALIDATION=1`, device from the `--device` flag.
    pub fn from_env(device_index: Option<usize>, requirements: Requirements) -> Self {
        let validation = std::env::var("SENSORLIGHT_VALIDATION").is_ok_and(|v| v == "1");
        Self { validation, device_index, requirements, window: None }
    }
}

pub struct Device {
    pub raw: ash::Device,
    pub adapter: Adapter,
    /// Submissions to a queue must not overlap (Vulkan's external synchronisation rule).
    pub(super) queue: Mutex<vk::Queue>,
    pub queue_family: u32,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    /// For one-off submissions (`submit_and_wait`, in `submit.rs`).
    pub(super) submitter: Mutex<Submitter>,
    // Declared last: dropped after `Drop::drop` has destroyed the device, the surface before the instance.
    surface: Option<Surface>,
    instance: Instance,
}

/// A reusable command buffer and fence for record-submit-wait work.
pub(super) struct Submitter {
    pool: vk::CommandPool,
    pub(super) cmd: vk::CommandBuffer,
    pub(super) fence: vk::Fence,
}

impl Device {
    pub fn new(options: &DeviceOptions) -> Result<Arc<Self>> {
        let wanted = match &options.window {
            Some(window) => window.instance_extensions()?,
            None => &[],
        };
        let instance = Instance::new(options.validation, wanted)?;
        let surface = options.window.as_ref().map(|w| Surface::new(&instance, w)).transpose()?;
        let mut adapters = adapter::enumerate(&instance, &options.requirements)?;
        if let Some(surface) = &surface {
            for a in &mut adapters {
                if a.queue_family.is_some_and(|family| !surface.supports(a.handle, family)) {
                    a.missing.push("its queue cannot present to the window".into());
                }
            }
        }
        let adapter = adapter::select(&adapters, options.device_index)?.clone();
        let queue_family = adapter.queue_family.expect("selected adapters have a queue family");

        let f = adapter.features;
        let mut features12 = vk::PhysicalDeviceVulkan12Features::default()
            .shader_output_layer(f.shader_output_layer)
            .draw_indirect_count(f.draw_indirect_count);
        let mut features11 = vk::PhysicalDeviceVulkan11Features::default().multiview(f.multiview);
        let core = vk::PhysicalDeviceFeatures::default()
            .shader_clip_distance(f.shader_clip_distance)
            .multi_draw_indirect(f.multi_draw_indirect)
            .draw_indirect_first_instance(f.draw_indirect_first_instance);
        let mut features =
            vk::PhysicalDeviceFeatures2::default().features(core).push_next(&mut features12).push_next(&mut features11);
        let priorities = [1.0];
        let queues =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
        let swapchain = [ash::khr::swapchain::NAME.as_ptr()];
        let extensions: &[_] = if surface.is_some() { &swapchain } else { &[] };
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(extensions)
            .push_next(&mut features);
        // SAFETY: the physical device comes from this instance; every pointer outlives the call.
        let raw = unsafe {
            let _loader = loader_lock();
            instance.raw.create_device(adapter.handle, &info, None)
        }
        .with_context(|| format!("cannot create a Vulkan device on {adapter}"))?;
        // SAFETY: queue 0 of a family we asked one queue of.
        let queue = unsafe { raw.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.raw.clone(),
            device: raw.clone(),
            physical_device: adapter.handle,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: nothing was created from the device yet.
                unsafe { destroy_raw(&raw) };
                return Err(e).context("cannot create the memory allocator");
            }
        };
        let submitter = match Submitter::new(&raw, queue_family) {
            Ok(s) => s,
            Err(e) => {
                drop(allocator);
                // SAFETY: the allocator (the only child) is gone.
                unsafe { destroy_raw(&raw) };
                return Err(e);
            }
        };
        Ok(Arc::new(Self {
            raw,
            adapter,
            queue: Mutex::new(queue),
            queue_family,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            submitter: Mutex::new(submitter),
            surface,
            instance,
        }))
    }

    /// What the validation layer reported so far. Keep a clone to read it after the device is gone.
    pub fn validation_log(&self) -> &Arc<ValidationLog> {
        self.instance.log()
    }

    /// The window's surface, where the device was opened for one ([`DeviceOptions::window`]).
    pub fn surface(&self) -> Option<&Surface> {
        self.surface.as_ref()
    }

    /// Waits until the device has nothing left to do (the queue taken meanwhile: Vulkan asks that every
    /// queue be synchronised for this).
    pub fn wait_idle(&self) -> Result<()> {
        let _queue = self.queue();
        // SAFETY: the one queue is held above.
        unsafe { self.raw.device_wait_idle() }.context("vkDeviceWaitIdle")
    }

    /// The queue, for submitting or presenting; held for as little as possible.
    pub(super) fn queue(&self) -> MutexGuard<'_, vk::Queue> {
        self.queue.lock().unwrap()
    }

    pub(super) fn instance(&self) -> &Instance {
        &self.instance
    }

    pub fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap()
    }
}

impl Submitter {
    fn new(device: &ash::Device, queue_family: u32) -> Result<Self> {
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: plain object creation on a valid device; on failure what was created is destroyed.
        unsafe {
            let pool = device.create_command_pool(&info, None)?;
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            let cmd = match device.allocate_command_buffers(&alloc) {
                Ok(c) => c[0],
                Err(e) => {
                    device.destroy_command_pool(pool, None);
                    return Err(e.into());
                }
            };
            let fence = match device.create_fence(&vk::FenceCreateInfo::default(), None) {
                Ok(f) => f,
                Err(e) => {
                    device.destroy_command_pool(pool, None);
                    return Err(e.into());
                }
            };
            Ok(Self { pool, cmd, fence })
        }
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: every child object holds an `Arc<Device>`, so all of them are gone; waiting idle makes the
        // submitter's objects free to destroy. The allocator frees its memory blocks before the device goes.
        unsafe {
            let _ = self.raw.device_wait_idle();
            let submitter = self.submitter.get_mut().unwrap();
            self.raw.destroy_fence(submitter.fence, None);
            self.raw.destroy_command_pool(submitter.pool, None);
            ManuallyDrop::drop(&mut self.allocator);
            destroy_raw(&self.raw);
        }
    }
}

/// Destroys a logical device under the loader's lock ([`loader_lock`]).
///
/// # Safety
/// Every object created from `raw` is destroyed and no other thread uses it.
unsafe fn destroy_raw(raw: &ash::Device) {
    let _loader = loader_lock();
    // SAFETY: the caller's.
    unsafe { raw.destroy_device(None) };
}
