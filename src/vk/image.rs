//! 2D and 2D-array images with their memory and views.

use std::sync::Arc;

use anyhow::{Context as _, Result, ensure};
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};

use super::device::Device;

#[derive(Clone, Copy, Debug)]
pub struct ImageDesc {
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub usage: vk::ImageUsageFlags,
    /// `TYPE_2D` (one layer) or `TYPE_2D_ARRAY`: what shaders declare (`image2D` vs `image2DArray`).
    pub view_type: vk::ImageViewType,
}

pub struct Image {
    device: Arc<Device>,
    pub raw: vk::Image,
    /// A view of every layer, of `desc.view_type`.
    pub view: vk::ImageView,
    allocation: Option<Allocation>,
    pub desc: ImageDesc,
}

pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D16_UNORM | vk::Format::D32_SFLOAT | vk::Format::X8_D24_UNORM_PACK32 => vk::ImageAspectFlags::DEPTH,
        vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT | vk::Format::D16_UNORM_S8_UINT => {
            vk::ImageAspectFlags::DEPTH // stencil is never sampled or cleared separately here
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

impl Image {
    pub fn new(device: &Arc<Device>, name: &str, desc: ImageDesc) -> Result<Self> {
        let limits = &device.adapter.limits;
        ensure!(
            desc.width >= 1 && desc.height >= 1 && desc.width.max(desc.height) <= limits.max_image_dimension_2d,
            "image {name} of {}x{} exceeds the device's limit of {} pixels per side",
            desc.width,
            desc.height,
            limits.max_image_dimension_2d
        );
        ensure!(
            desc.layers >= 1 && desc.layers <= limits.max_image_array_layers,
            "image {name} with {} layers exceeds the device's limit of {}",
            desc.layers,
            limits.max_image_array_layers
        );
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width, height: desc.height, depth: 1 })
            .mip_levels(1)
            .array_layers(desc.layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device and create info (limits checked above).
        let raw = unsafe { device.raw.create_image(&info, None) }.with_context(|| format!("create image {name}"))?;
        // SAFETY: `raw` was just created on this device.
        let requirements = unsafe { device.raw.get_image_memory_requirements(raw) };
        let allocation = device.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: no memory bound, not in use.
                unsafe { device.raw.destroy_image(raw, None) };
                return Err(e).with_context(|| format!("allocate {} bytes for image {name}", requirements.size));
            }
        };
        let mut image =
            Self { device: device.clone(), raw, view: vk::ImageView::null(), allocation: Some(allocation), desc };
        let a = image.allocation.as_ref().unwrap();
        // SAFETY: memory from the allocator matches the image's requirements.
        unsafe { device.raw.bind_image_memory(raw, a.memory(), a.offset()) }?;
        image.view = image.create_view(desc.view_type, 0, desc.layers)?;
        Ok(image)
    }

    /// A view of layers `first..first + count`. The caller owns it (see [`ImageView`]).
    fn create_view(&self, view_type: vk::ImageViewType, first: u32, count: u32) -> Result<vk::ImageView> {
        let info = vk::ImageViewCreateInfo::default()
            .image(self.raw)
            .view_type(view_type)
            .format(self.desc.format)
            .subresource_range(self.range(first, count));
        // SAFETY: the range lies inside the image.
        Ok(unsafe { self.device.raw.create_image_view(&info, None) }?)
    }

    pub fn range(&self, first: u32, count: u32) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default()
            .aspect_mask(aspect_of(self.desc.format))
            .base_mip_level(0)
            .level_count(1)
            .base_array_layer(first)
            .layer_count(count)
    }

    pub fn full_range(&self) -> vk::ImageSubresourceRange {
        self.range(0, self.desc.layers)
    }

    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D { width: self.desc.width, height: self.desc.height }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: owners wait for the GPU before dropping what it uses; the view goes before the image.
        unsafe { self.device.raw.destroy_image_view(self.view, None) };
        if let Some(allocation) = self.allocation.take() {
            let _ = self.device.allocator().free(allocation);
        }
        unsafe { self.device.raw.destroy_image(self.raw, None) };
    }
}

/// A view of some layers of an image that keeps the image alive: a framebuffer owns the views it was made
/// from, so no field order has to keep an image from being destroyed under its views.
pub struct ImageView {
    image: Arc<Image>,
    pub raw: vk::ImageView,
}

impl ImageView {
    /// A 2D-array view of layers `first..first + count` of `image`.
    pub fn layers(image: &Arc<Image>, first: u32, count: u32) -> Result<Self> {
        ensure!(first + count <= image.desc.layers, "layers {first}..{} out of {}", first + count, image.desc.layers);
        let raw = image.create_view(vk::ImageViewType::TYPE_2D_ARRAY, first, count)?;
        Ok(Self { image: image.clone(), raw })
    }

    /// A view of all of `image`, of its own view type.
    pub fn whole(image: &Arc<Image>) -> Result<Self> {
        let raw = image.create_view(image.desc.view_type, 0, image.desc.layers)?;
        Ok(Self { image: image.clone(), raw })
    }

    pub fn image(&self) -> &Arc<Image> {
        &self.image
    }
}

impl Drop for ImageView {
    fn drop(&mut self) {
        // SAFETY: owners wait for the GPU before dropping what it uses; the image outlives this view.
        unsafe { self.image.device.raw.destroy_image_view(self.raw, None) };
    }
}
