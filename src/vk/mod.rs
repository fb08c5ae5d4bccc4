//! The Vulkan layer: one file per concept. Each handle is owned by one Drop type holding an `Arc<Device>`,
//! so the device (and the instance inside it) outlives everything made from it.

pub mod adapter;
pub mod barrier;
pub mod buffer;
pub mod compute;
pub mod descriptor;
pub mod device;
pub mod image;
pub mod instance;
pub mod pipeline;
pub mod render_pass;
pub mod transfer;
pub mod validation;

pub use adapter::Adapter;
pub use buffer::Buffer;
pub use compute::ComputeKernel;
pub use descriptor::{DescriptorPool, SetWriter};
pub use device::{Device, DeviceOptions};
pub use image::{Image, ImageDesc};
pub use pipeline::{GraphicsDesc, Pipeline, PipelineLayout};
pub use render_pass::{Framebuffer, RenderPass};
