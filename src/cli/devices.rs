//! `sensorlight devices`: what Vulkan reports, and which device `render` would pick.

use std::process::ExitCode;

use anyhow::Result;
use sensorlight::outln;
use sensorlight::vk::adapter::{self, version_string};
use sensorlight::vk::instance::Instance;

pub fn run() -> Result<ExitCode> {
    let instance = Instance::new(false, &[])?;
    let adapters = adapter::enumerate(&instance, &sensorlight::passes::requirements())?;
    let chosen = adapter::select(&adapters, None).ok().map(|a| a.index);
    for a in &adapters {
        let l = &a.limits;
        let f = &a.features;
        let yes = |b: bool| if b { "yes" } else { "no" };
        let mark = if Some(a.index) == chosen { "  (default)" } else { "" };
        outln!("[{}] {}{mark}", a.index, a.name)?;
        outln!("    type {}, driver {}, Vulkan {}", a.kind_name(), a.driver, version_string(a.api_version))?;
        outln!(
            "    maxMultiviewViewCount {}, maxFramebufferLayers {}, shaderOutputLayer {}, multiview {}, clip distance {}",
            l.max_multiview_view_count,
            l.max_framebuffer_layers,
            yes(f.shader_output_layer),
            yes(f.multiview),
            yes(f.shader_clip_distance)
        )?;
        outln!(
            "    maxImageDimension2D {}, maxImageArrayLayers {}, compute shared memory {} KiB, device-local heap {:.1} GiB",
            l.max_image_dimension_2d,
            l.max_image_array_layers,
            l.max_compute_shared_memory_size / 1024,
            a.device_local_bytes as f64 / (1u64 << 30) as f64
        )?;
        if let Some(why) = a.unsupported_reason() {
            outln!("    unsupported: {why}")?;
        }
    }
    Ok(ExitCode::SUCCESS)
}
