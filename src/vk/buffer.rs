//! Buffers with their memory. Host-visible ones are mapped for the life of the buffer.

use std::sync::Arc;

use anyhow::{Context as _, Result, ensure};
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};

use super::device::Device;

pub struct Buffer {
    device: Arc<Device>,
    pub raw: vk::Buffer,
    allocation: Option<Allocation>,
    pub size: u64,
}

impl Buffer {
    /// A buffer of `size` bytes (at least 4: Vulkan forbids empty buffers, and empty inputs still bind).
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let size = size.max(4);
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info.
        let raw = unsafe { device.raw.create_buffer(&info, None) }.with_context(|| format!("create buffer {name}"))?;
        // SAFETY: `raw` was just created on this device.
        let requirements = unsafe { device.raw.get_buffer_memory_requirements(raw) };
        let allocation = device.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer has no memory bound and is not in use.
                unsafe { device.raw.destroy_buffer(raw, None) };
                return Err(e).with_context(|| format!("allocate {size} bytes for buffer {name}"));
            }
        };
        // Owned from here on: `Drop` cleans up if binding fails.
        let buffer = Self { device: device.clone(), raw, allocation: Some(allocation), size };
        let a = buffer.allocation.as_ref().unwrap();
        // SAFETY: memory from the allocator matches the buffer's requirements.
        unsafe { device.raw.bind_buffer_memory(raw, a.memory(), a.offset()) }?;
        Ok(buffer)
    }

    /// Writes `data` at byte `offset` of a host-visible buffer.
    pub fn write<T: bytemuck::Pod>(&mut self, offset: usize, data: &[T]) -> Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mapped =
            self.allocation.as_mut().and_then(|a| a.mapped_slice_mut()).context("buffer is not host-visible")?;
        ensure!(
            offset + bytes.len() <= mapped.len(),
            "write of {} bytes at {offset} overflows the buffer",
            bytes.len()
        );
        mapped[offset..offset + bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    /// Copies the first `count` elements out of a host-visible buffer.
    pub fn read<T: bytemuck::Pod>(&self, count: usize) -> Result<Vec<T>> {
        let mapped = self.allocation.as_ref().and_then(|a| a.mapped_slice()).context("buffer is not host-visible")?;
        let bytes = count * size_of::<T>();
        ensure!(bytes <= mapped.len(), "read of {bytes} bytes overflows a buffer of {}", mapped.len());
        // `pod_collect_to_vec` copies, so the mapped bytes need no particular alignment.
        Ok(bytemuck::pod_collect_to_vec(&mapped[..bytes]))
    }

    pub fn descriptor(&self) -> vk::DescriptorBufferInfo {
        vk::DescriptorBufferInfo::default().buffer(self.raw).offset(0).range(vk::WHOLE_SIZE)
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(allocation) = self.allocation.take() {
            let _ = self.device.allocator().free(allocation);
        }
        // SAFETY: owners wait for the GPU before dropping what it uses.
        unsafe { self.device.raw.destroy_buffer(self.raw, None) };
    }
}
