//! Radiance HDR (RGBE) output: a lightmap for engines that load `.hdr` rather than EXR (`sensorlight bake
//! --format hdr`). Shared exponent, 8-bit mantissas: about 1 % precision over a wide range.

use std::io::Write;

use anyhow::Result;
use glam::Vec3;

/// Encodes `width` × `height` linear RGB, row-major from the top.
pub fn encode(w: &mut impl Write, width: u32, height: u32, rgb: &[Vec3]) -> Result<()> {
    let pixels: Vec<image::Rgb<f32>> = rgb.iter().map(|c| image::Rgb(c.to_array())).collect();
    image::codecs::hdr::HdrEncoder::new(w).encode(&pixels, width as usize, height as usize)?;
    Ok(())
}
