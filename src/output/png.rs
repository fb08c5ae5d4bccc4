//! A tone-mapped preview: linear radiance × 2^exposure, clamped, sRGB-encoded, 8-bit PNG.

use std::io::Write;
use std::path::Path;

use anyhow::Result;
use glam::Vec4;

use super::atomic;

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1].
pub fn srgb_encode(linear: f32) -> f32 {
    let x = linear.clamp(0.0, 1.0);
    if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 }
}

/// 8-bit sRGB bytes (RGB) of `pixels` scaled by `2^exposure`.
pub fn tone_map(pixels: &[Vec4], exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    pixels.iter().flat_map(|p| [p.x, p.y, p.z].map(|c| (srgb_encode(c * scale) * 255.0 + 0.5) as u8)).collect()
}

/// Writes the tone-mapped image atomically.
pub fn write(path: &Path, width: u32, height: u32, pixels: &[Vec4], exposure: f32) -> Result<()> {
    write_rgb8(path, width, height, &tone_map(pixels, exposure))
}

/// Stages the tone-mapped image among `outputs` (written with the others, or not at all).
pub fn stage(
    outputs: &mut atomic::Outputs,
    path: &Path,
    (width, height): (u32, u32),
    pixels: &[Vec4],
    exposure: f32,
) -> Result<()> {
    let rgb = tone_map(pixels, exposure);
    outputs.stage(path, |w| encode_rgb8(w, width, height, &rgb))
}

/// Writes 8-bit sRGB RGB bytes, row-major from the top, as a PNG, atomically.
pub fn write_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    atomic::write_file(path, |w| encode_rgb8(w, width, height, rgb))
}

/// Encodes 8-bit sRGB RGB bytes as a PNG into `w`.
pub fn encode_rgb8(w: &mut impl Write, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    let mut encoder = png::Encoder::new(w, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints_and_midpoint() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_encode(0.2140) - 0.5).abs() < 1e-3); // 50 % grey is 21.4 % linear
        assert_eq!(tone_map(&[Vec4::new(4.0, 0.5, -1.0, 1.0)], -2.0)[..], [255, 99, 0]); // 0.125 linear is 38.9 % sRGB
    }
}
