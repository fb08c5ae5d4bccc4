//! The Vulkan layer: one file per concept. Each handle is owned by one Drop type holding an `Arc<Device>`,
//! so the device (and the instance inside it) outlives everything made from it. This layer knows nothing of
//! the renderer: passes state what they need of a device as [`Requirements`].

pub mod adapter;
pub mod barrier;
pub mod buffer;
pub mod compute;
pub mod descriptor;
pub mod device;
pub mod encoder;
pub mod image;
pub mod instance;
pub mod pipeline;
pub mod query;
pub mod render_pass;
pub mod slot;
pub mod submit;
pub mod surface;
pub mod swapchain;
pub mod transfer;
pub mod validation;

pub use adapter::{Adapter, Requirements};
pub use barrier::Access;
pub use buffer::Buffer;
pub use compute::ComputeKernel;
pub use descriptor::{DescriptorPool, SetWriter};
pub use device::{Device, DeviceOptions};
pub use encoder::{Encoder, RenderPassScope};
pub use image::{Image, ImageDesc, ImageView};
pub use pipeline::{GraphicsDesc, Pipeline, PipelineLayout};
pub use query::TimestampQueries;
pub use render_pass::{Framebuffer, RenderPass};
pub use slot::CommandSlot;
pub use surface::WindowTarget;
pub use swapchain::Swapchain;
