//! GPU passes, one file each, in pipeline order (docs/DESIGN.md §3). Each pass owns its pipeline, layouts and
//! descriptors and is named after the shaders it runs (`glsl/<pass>.*`).

pub mod compose;
pub mod cull;
pub mod cull_triangles;
pub mod emitters;
pub mod fill;
pub mod filter;
pub mod gbuffer;
pub mod interpolate;
pub mod reduce;
pub mod resolve;
pub mod sensor_maps;
pub mod transport;

use ash::vk;

use crate::vk::Requirements;

/// Depth format of every raster pass. Floats because the projections are reversed-Z (1 at the near plane,
/// 0 at infinity), which keeps precision only with a floating-point depth buffer.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// Reversed-Z: nearer is larger.
pub const DEPTH_COMPARE: vk::CompareOp = vk::CompareOp::GREATER;

/// What the passes need of a device beyond Vulkan 1.2: every image format they create, with the features
/// they use it with (all but `D32_SFLOAT` are mandatory in Vulkan 1.2, which lets a device offer `X8_D24`
/// depth instead), and the G-buffer's colour attachments (the spec's minimum is 4, the G-buffer has 5).
pub fn requirements() -> Requirements {
    let colour = vk::FormatFeatureFlags::COLOR_ATTACHMENT | vk::FormatFeatureFlags::STORAGE_IMAGE;
    let mut formats: Vec<_> = gbuffer::COLOR_FORMATS.iter().map(|&f| (f, colour)).collect();
    formats.push((sensor_maps::MAP_FORMAT, colour));
    formats.push((DEPTH_FORMAT, vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT));
    formats.dedup();
    Requirements { formats, color_attachments: gbuffer::ATTACHMENT_COUNT }
}
