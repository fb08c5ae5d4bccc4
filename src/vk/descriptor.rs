//! Descriptor pools, and a small builder for `vkUpdateDescriptorSets`.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use super::buffer::Buffer;
use super::device::Device;
use super::pipeline::PipelineLayout;

/// A pool sized for `sets` sets of one layout; freeing the pool frees its sets.
pub struct DescriptorPool {
    device: Arc<Device>,
    pub raw: vk::DescriptorPool,
}

impl DescriptorPool {
    /// `per_set`: how many descriptors of each type one set holds.
    pub fn new(device: &Arc<Device>, sets: u32, per_set: &[(vk::DescriptorType, u32)]) -> Result<Self> {
        let sizes: Vec<_> = per_set
            .iter()
            .map(|&(ty, count)| vk::DescriptorPoolSize::default().ty(ty).descriptor_count(count * sets))
            .collect();
        let info = vk::DescriptorPoolCreateInfo::default().max_sets(sets).pool_sizes(&sizes);
        // SAFETY: valid device and create info.
        let raw = unsafe { device.raw.create_descriptor_pool(&info, None) }?;
        Ok(Self { device: device.clone(), raw })
    }

    pub fn allocate(&self, layout: &PipelineLayout) -> Result<vk::DescriptorSet> {
        let layouts = [layout.set_layout];
        let info = vk::DescriptorSetAllocateInfo::default().descriptor_pool(self.raw).set_layouts(&layouts);
        // SAFETY: the pool was sized by its owner for the sets it allocates.
        Ok(unsafe { self.device.raw.allocate_descriptor_sets(&info) }?[0])
    }
}

impl Drop for DescriptorPool {
    fn drop(&mut self) {
        // SAFETY: owners wait for the GPU before dropping what it uses.
        unsafe { self.device.raw.destroy_descriptor_pool(self.raw, None) };
    }
}

/// Collects writes to one descriptor set, then applies them in one call.
pub struct SetWriter {
    set: vk::DescriptorSet,
    buffers: Vec<(u32, vk::DescriptorType, vk::DescriptorBufferInfo)>,
    images: Vec<(u32, vk::DescriptorType, vk::DescriptorImageInfo)>,
}

impl SetWriter {
    pub fn new(set: vk::DescriptorSet) -> Self {
        Self { set, buffers: Vec::new(), images: Vec::new() }
    }

    pub fn storage_buffer(mut self, binding: u32, buffer: &Buffer) -> Self {
        self.buffers.push((binding, vk::DescriptorType::STORAGE_BUFFER, buffer.descriptor()));
        self
    }

    /// A storage image, in `GENERAL` layout when used.
    pub fn storage_image(mut self, binding: u32, view: vk::ImageView) -> Self {
        let info = vk::DescriptorImageInfo::default().image_view(view).image_layout(vk::ImageLayout::GENERAL);
        self.images.push((binding, vk::DescriptorType::STORAGE_IMAGE, info));
        self
    }

    pub fn apply(self, device: &Device) {
        let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = self.buffers.iter().map(|b| [b.2]).collect();
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = self.images.iter().map(|i| [i.2]).collect();
        let mut writes = Vec::new();
        for ((binding, ty, _), info) in self.buffers.iter().zip(&buffer_infos) {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(*binding)
                    .descriptor_type(*ty)
                    .buffer_info(info),
            );
        }
        for ((binding, ty, _), info) in self.images.iter().zip(&image_infos) {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(*binding)
                    .descriptor_type(*ty)
                    .image_info(info),
            );
        }
        // SAFETY: the set is not in use by the GPU while it is updated (owners write before recording).
        unsafe { device.raw.update_descriptor_sets(&writes, &[]) };
    }
}
