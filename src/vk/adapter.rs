//! Physical devices ("adapters"): what they are, the limits this program depends on, and which one to use.
//! What the program needs of a device is stated by its callers ([`Requirements`]), so this layer knows no
//! pass.

use std::fmt;

use anyhow::{Result, bail};
use ash::vk;

use super::instance::{INSTALL_HINT, Instance};

/// The limits and features that decide batch sizes and which sensor strategies can run.
#[derive(Clone, Debug, Default)]
pub struct Limits {
    pub max_image_dimension_2d: u32,
    pub max_image_array_layers: u32,
    pub max_framebuffer_layers: u32,
    pub max_framebuffer_width: u32,
    pub max_framebuffer_height: u32,
    pub max_multiview_view_count: u32,
    pub max_color_attachments: u32,
    pub max_compute_shared_memory_size: u32,
    pub max_compute_work_group_invocations: u32,
    pub max_compute_work_group_count: [u32; 3],
    pub max_storage_buffer_range: u32,
    pub max_push_constants_size: u32,
    pub max_memory_allocation_size: u64,
    /// Most draws one indirect draw command may read.
    pub max_draw_indirect_count: u32,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
}

/// What the program needs of a device beyond Vulkan 1.2 with a graphics-and-compute queue: stated by the
/// passes that use it (`passes::requirements`).
#[derive(Clone, Debug, Default)]
pub struct Requirements {
    /// Image formats with the features used with them (optimal tiling).
    pub formats: Vec<(vk::Format, vk::FormatFeatureFlags)>,
    /// Colour attachments of the widest render pass.
    pub color_attachments: u32,
}

/// Optional features; the device is created with every one that is present.
#[derive(Clone, Copy, Debug, Default)]
pub struct Features {
    /// `gl_Layer` written from the vertex shader (Vulkan 1.2 `shaderOutputLayer`): layered sensor rendering.
    pub shader_output_layer: bool,
    /// `VK_KHR_multiview` (core in 1.1).
    pub multiview: bool,
    /// `gl_ClipDistance`: two half hemicube faces share one layer.
    pub shader_clip_distance: bool,
    /// `vkCmdDrawIndexedIndirectCount` (Vulkan 1.2 `drawIndirectCount`): the device reads how many draws.
    pub draw_indirect_count: bool,
    /// Indirect draws with more than one command (`multiDrawIndirect`).
    pub multi_draw_indirect: bool,
    /// Indirect commands with a non-zero `firstInstance` (`drawIndirectFirstInstance`).
    pub draw_indirect_first_instance: bool,
}

#[derive(Clone, Debug)]
pub struct Adapter {
    /// Position in `vkEnumeratePhysicalDevices`, the number `--device` takes.
    pub index: usize,
    pub handle: vk::PhysicalDevice,
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    pub driver: String,
    pub api_version: u32,
    /// A queue family with graphics and compute, if any.
    pub queue_family: Option<u32>,
    /// Valid bits of that family's timestamps; 0 where it cannot write timestamps.
    pub timestamp_valid_bits: u32,
    /// Size of the largest device-local heap, in bytes.
    pub device_local_bytes: u64,
    pub limits: Limits,
    pub features: Features,
    /// What [`Requirements`] asks for and this device lacks, in words.
    pub missing: Vec<String>,
}

impl Adapter {
    /// Whether this program can run on it at all, and if not, why.
    pub fn unsupported_reason(&self) -> Option<String> {
        if self.api_version < vk::API_VERSION_1_2 {
            return Some(format!("Vulkan {} < 1.2", version_string(self.api_version)));
        }
        if self.queue_family.is_none() {
            return Some("no queue family with graphics and compute".into());
        }
        if !self.missing.is_empty() {
            return Some(self.missing.join(", "));
        }
        None
    }

    /// Preference order: discrete GPU, integrated GPU, virtual GPU, CPU (e.g. lavapipe), anything else.
    fn rank(&self) -> u32 {
        match self.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => 0,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            vk::PhysicalDeviceType::CPU => 3,
            _ => 4,
        }
    }

    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        }
    }
}

impl fmt::Display for Adapter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({}, {})", self.name, self.kind_name(), self.driver)
    }
}

pub fn version_string(v: u32) -> String {
    format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
}

/// Every physical device the loader reports, in its order, each judged against `requirements`.
pub fn enumerate(instance: &Instance, requirements: &Requirements) -> Result<Vec<Adapter>> {
    let raw = &instance.raw;
    // Under the loader's lock too: the first enumeration on an instance is where the loader and the driver
    // set up their physical devices (lavapipe its screen), as process-wide as a device's creation. A test
    // that opens devices on 8 threads at once crashed once under load on Mesa 22.3 (not reproduced since).
    let _loader = super::instance::loader_lock();
    // SAFETY: queries on a valid instance.
    let handles = unsafe { raw.enumerate_physical_devices() }?;
    if handles.is_empty() {
        bail!("no Vulkan device found; {INSTALL_HINT}");
    }
    Ok(handles.into_iter().enumerate().map(|(index, handle)| describe(instance, index, handle, requirements)).collect())
}

fn describe(instance: &Instance, index: usize, handle: vk::PhysicalDevice, requirements: &Requirements) -> Adapter {
    let raw = &instance.raw;
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut multiview = vk::PhysicalDeviceMultiviewProperties::default();
    let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut props = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut driver)
        .push_next(&mut multiview)
        .push_next(&mut maintenance3);
    let mut features12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut features11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut features12).push_next(&mut features11);
    // SAFETY: queries on a valid physical device; the chained structs outlive the calls.
    let (families, memory) = unsafe {
        raw.get_physical_device_properties2(handle, &mut props);
        raw.get_physical_device_features2(handle, &mut features);
        (raw.get_physical_device_queue_family_properties(handle), raw.get_physical_device_memory_properties(handle))
    };
    // Copied out so that the chain's borrows of `features11`/`features12` end before they are read.
    let core_features = features.features;
    let p = props.properties;
    let l = &p.limits;
    let wanted = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    let queue_family = families.iter().position(|f| f.queue_flags.contains(wanted)).map(|i| i as u32);
    let timestamp_valid_bits = queue_family.map_or(0, |f| families[f as usize].timestamp_valid_bits);
    let device_local_bytes = memory.memory_heaps[..memory.memory_heap_count as usize]
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or(0);
    let name = p.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let driver_name = driver.driver_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let mut missing: Vec<String> = requirements
        .formats
        .iter()
        .filter(|&&(format, needed)| {
            // SAFETY: a query on a valid physical device.
            let have = unsafe { raw.get_physical_device_format_properties(handle, format) }.optimal_tiling_features;
            !have.contains(needed)
        })
        .map(|(format, needed)| format!("unsupported format {format:?} as {needed:?}"))
        .collect();
    if p.limits.max_color_attachments < requirements.color_attachments {
        missing.push(format!(
            "only {} colour attachments (needs {})",
            p.limits.max_color_attachments, requirements.color_attachments
        ));
    }
    let driver_info = driver.driver_info_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    Adapter {
        index,
        handle,
        name,
        kind: p.device_type,
        driver: format!("{driver_name} {driver_info}").trim().to_owned(),
        api_version: p.api_version,
        queue_family,
        timestamp_valid_bits,
        device_local_bytes,
        limits: Limits {
            max_image_dimension_2d: l.max_image_dimension2_d,
            max_image_array_layers: l.max_image_array_layers,
            max_framebuffer_layers: l.max_framebuffer_layers,
            max_framebuffer_width: l.max_framebuffer_width,
            max_framebuffer_height: l.max_framebuffer_height,
            max_multiview_view_count: multiview.max_multiview_view_count,
            max_color_attachments: l.max_color_attachments,
            max_compute_shared_memory_size: l.max_compute_shared_memory_size,
            max_compute_work_group_invocations: l.max_compute_work_group_invocations,
            max_compute_work_group_count: l.max_compute_work_group_count,
            max_storage_buffer_range: l.max_storage_buffer_range,
            max_push_constants_size: l.max_push_constants_size,
            max_memory_allocation_size: maintenance3.max_memory_allocation_size,
            max_draw_indirect_count: l.max_draw_indirect_count,
            timestamp_period: l.timestamp_period,
        },
        features: Features {
            shader_output_layer: features12.shader_output_layer == vk::TRUE,
            multiview: features11.multiview == vk::TRUE,
            shader_clip_distance: core_features.shader_clip_distance == vk::TRUE,
            draw_indirect_count: features12.draw_indirect_count == vk::TRUE,
            multi_draw_indirect: core_features.multi_draw_indirect == vk::TRUE,
            draw_indirect_first_instance: core_features.draw_indirect_first_instance == vk::TRUE,
        },
        missing,
    }
}

/// The adapter to use: `requested` (an index into `adapters`) or the best supported one.
pub fn select(adapters: &[Adapter], requested: Option<usize>) -> Result<&Adapter> {
    if let Some(index) = requested {
        let Some(adapter) = adapters.get(index) else {
            bail!("there is no device {index}: {} device(s) found", adapters.len());
        };
        if let Some(why) = adapter.unsupported_reason() {
            bail!("device {index} ({adapter}) cannot run sensorlight: {why}");
        }
        return Ok(adapter);
    }
    adapters.iter().filter(|a| a.unsupported_reason().is_none()).min_by_key(|a| (a.rank(), a.index)).ok_or_else(|| {
        let found: Vec<String> =
            adapters.iter().map(|a| format!("{a}: {}", a.unsupported_reason().unwrap_or_default())).collect();
        anyhow::anyhow!("no usable Vulkan device (found: {}); {INSTALL_HINT}", found.join("; "))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adapter(index: usize, kind: vk::PhysicalDeviceType, missing: &[&str]) -> Adapter {
        Adapter {
            index,
            handle: vk::PhysicalDevice::null(),
            name: format!("device {index}"),
            kind,
            driver: "test".into(),
            api_version: vk::API_VERSION_1_3,
            queue_family: Some(0),
            timestamp_valid_bits: 64,
            device_local_bytes: 1 << 30,
            limits: Limits { max_color_attachments: 8, ..Limits::default() },
            features: Features::default(),
            missing: missing.iter().map(|s| s.to_string()).collect(),
        }
    }

    #[test]
    fn prefers_a_gpu_and_skips_devices_that_lack_a_format() {
        let cpu = adapter(0, vk::PhysicalDeviceType::CPU, &[]);
        let gpu = adapter(1, vk::PhysicalDeviceType::DISCRETE_GPU, &[]);
        let no_depth = adapter(
            2,
            vk::PhysicalDeviceType::DISCRETE_GPU,
            &["unsupported format D32_SFLOAT as DEPTH_STENCIL_ATTACHMENT"],
        );
        // In enumeration order, as `enumerate` returns them.
        let all = [cpu.clone(), gpu, no_depth.clone()];
        assert_eq!(select(&all, None).unwrap().index, 1);
        assert_eq!(select(&[no_depth.clone(), cpu], None).unwrap().index, 0);

        let err = select(std::slice::from_ref(&no_depth), None).unwrap_err().to_string();
        assert!(err.contains("D32_SFLOAT"), "{err}");
        assert_eq!(select(&all, Some(0)).unwrap().index, 0, "an explicit --device is honoured");
        let err = select(&all, Some(2)).unwrap_err().to_string();
        assert!(err.contains("device 2") && err.contains("unsupported format"), "{err}");
        let err = select(&all, Some(7)).unwrap_err().to_string();
        assert!(err.contains("no device 7: 3 device(s) found"), "{err}");
    }
}
