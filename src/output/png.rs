//! A tone-mapped preview. The operator is linear: radiance × 2^exposure, clipped to [0, 1] per channel,
//! sRGB-encoded, 8 bits (no tone curve, so a PNG value is a known radiance). A bare mesh's exposure is chosen
//! by [`auto_exposure`].

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

/// The luminance percentile [`auto_exposure`] maps to white: the brightest 1 % of lit pixels (highlights,
/// a small light's hot spot) may clip, the rest keeps its gradation.
pub const AUTO_PERCENTILE: f64 = 0.99;
/// Exposures [`auto_exposure`] keeps to, stops: beyond them the image is black or all light, whatever it is.
const AUTO_RANGE: f32 = 24.0;

/// Rec. 709 luminance of linear RGB.
pub fn luminance(p: Vec4) -> f32 {
    0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z
}

/// The exposure, in stops rounded to a tenth, that maps the [`AUTO_PERCENTILE`] of `lit` (the luminances of
/// the pixels to expose for; those ≤ 0 are left out) to white (1); `None` when none is lit.
pub fn auto_exposure(lit: impl IntoIterator<Item = f32>) -> Option<f32> {
    let mut y: Vec<f32> = lit.into_iter().filter(|&v| v > 0.0 && v.is_finite()).collect();
    if y.is_empty() {
        return None;
    }
    let k = ((AUTO_PERCENTILE * y.len() as f64).ceil() as usize).clamp(1, y.len()) - 1;
    let (_, &mut at, _) = y.select_nth_unstable_by(k, f32::total_cmp);
    let stops = (-at.log2()).clamp(-AUTO_RANGE, AUTO_RANGE);
    Some((stops * 10.0).round() / 10.0 + 0.0) // + 0.0: never −0
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
    encode_8bit(w, (width, height), png::ColorType::Rgb, rgb)
}

/// Encodes sRGB-encoded RGBA, 8 bits a channel, alpha linear (a baked scene's base colour textures).
pub fn encode_rgba8(w: &mut impl Write, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    encode_8bit(w, (width, height), png::ColorType::Rgba, rgba)
}

fn encode_8bit(w: &mut impl Write, (width, height): (u32, u32), color: png::ColorType, data: &[u8]) -> Result<()> {
    let mut encoder = png::Encoder::new(w, width, height);
    encoder.set_color(color);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(data)?;
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

    #[test]
    fn auto_exposure_maps_the_99th_percentile_to_white() {
        // 1000 pixels of luminance 0.01 … 10: the 990th is 9.9 → −3.3 stops.
        let ramp = (1..=1000).map(|i| i as f32 / 100.0);
        assert_eq!(auto_exposure(ramp), Some(-3.3));
        // A dim image is brightened: 1/16 → +4 stops; a few bright pixels above the percentile do not count.
        let dim = (0..1000).map(|i| if i < 5 { 50.0 } else { 0.0625 });
        assert_eq!(auto_exposure(dim), Some(4.0));
        assert_eq!(auto_exposure([1.0]), Some(0.0));
        assert_eq!(auto_exposure([0.0, -1.0, f32::NAN]), None, "nothing lit");
        assert_eq!(auto_exposure([1e-30]), Some(AUTO_RANGE), "kept to its range");
    }
}
