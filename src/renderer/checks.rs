//! What a render refuses before it uploads or writes anything: a sensor size, a cache or textures the device
//! cannot hold, an image that is not finite.

use anyhow::{Result, bail, ensure};
use glam::Vec4;

use super::config::RendererConfig;
use crate::params::{Param, ParamError};
use crate::scene::{Texture, texture};
use crate::vk::Device;

/// Never an image of NaN with success: whatever produced one (a driver, a bug) is an error, before anything
/// is written.
pub(super) fn check_finite(image: &[Vec4], width: usize, driver: &str) -> Result<()> {
    let non_finite = |v: &&Vec4| !v.truncate().is_finite();
    if let Some(first) = image.iter().position(|v| non_finite(&v)) {
        bail!(
            "the image has {} NaN or infinite pixel(s), the first at x {}, y {}: this is a bug in sensorlight or the \
             Vulkan driver ({driver}); nothing was written",
            image.iter().filter(non_finite).count(),
            first % width,
            first / width
        );
    }
    Ok(())
}

/// The radiance cache's table and values against the device: at most an eighth of its local memory (as the
/// batches in flight together), before anything is uploaded.
pub(super) fn check_cache_size(device: &Device, bytes: u64, resolution: u32) -> Result<()> {
    let most = device.adapter.device_local_bytes / 8;
    if bytes > most || bytes > device.adapter.limits.max_storage_buffer_range as u64 {
        let problem = format!(
            "{resolution} gives a radiance cache of at least {:.0} MiB, more than this device allows ({:.0} MiB, an \
             eighth of its memory, in storage buffers of at most {:.0} MiB); use fewer cells",
            bytes as f64 / (1 << 20) as f64,
            most as f64 / (1 << 20) as f64,
            device.adapter.limits.max_storage_buffer_range as f64 / (1 << 20) as f64
        );
        return Err(ParamError::new(Param::CacheResolution, problem).into());
    }
    Ok(())
}

/// The scene's textures against the device, before anything is uploaded: their levels together in one
/// storage buffer, at most a quarter of its local memory.
pub(super) fn check_textures(device: &Device, textures: &[Texture]) -> Result<()> {
    let bytes = texture::gpu_bytes(textures);
    let most = (device.adapter.device_local_bytes / 4).min(device.adapter.limits.max_storage_buffer_range as u64);
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    let largest = textures.iter().max_by_key(|t| t.texel_count());
    let largest = largest.map_or(String::new(), |t| {
        let own = texture::gpu_bytes(std::slice::from_ref(t));
        format!(" (the largest, {}, is {} × {}: {:.0} MiB)", t.name, t.width(), t.height(), mib(own))
    });
    ensure!(
        bytes <= most,
        "the scene's {} texture(s) need {:.0} MiB with their mipmaps{largest}, more than this device allows ({:.0} \
         MiB: a quarter of its memory, in one storage buffer); use smaller images",
        textures.len(),
        mib(bytes),
        mib(most)
    );
    Ok(())
}

/// The sensor size against the device's largest image and framebuffer side.
pub(super) fn check_size(device: &Device, config: &RendererConfig) -> Result<()> {
    let limits = &device.adapter.limits;
    let max = limits.max_image_dimension_2d.min(limits.max_framebuffer_width).min(limits.max_framebuffer_height);
    if let Some(problem) = config.sensor.size_problem(config.sensor_size, max) {
        return Err(ParamError::new(Param::SensorSize, problem).into());
    }
    match config.cache.and_then(|c| config.sensor.size_problem(c.sensor_size, max)) {
        Some(problem) => Err(ParamError::new(Param::CacheSensorSize, problem).into()),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_with_nan_or_inf_is_an_error_naming_the_first() {
        let mut image = vec![Vec4::ONE; 6];
        assert!(check_finite(&image, 3, "d").is_ok());
        image[4].y = f32::NAN;
        image[5].x = f32::INFINITY;
        let message = check_finite(&image, 3, "d").unwrap_err().to_string();
        assert!(message.contains("2 NaN or infinite pixel(s), the first at x 1, y 1"), "{message}");
        image[4].w = 0.0;
        image[4].y = 0.0;
        image[5] = Vec4::new(1.0, 1.0, 1.0, f32::NAN);
        assert!(check_finite(&image, 3, "d").is_ok(), "alpha is not part of the image");
    }
}
