//! Colour textures (`map_Kd`, glTF `baseColorTexture`): decoded once, mipmapped, and sampled the same way on
//! the CPU ([`Texture::sample`]) and in `glsl/texture.glsl`, from the same 8-bit sRGB texels.
//!
//! Texel layout on the GPU, one buffer for every texture of a scene (`GpuTexture::offset` is where each
//! begins):
//!
//! ```text
//!   level 0: width × height texels, row by row (row 0 is the image's top)
//!   level 1: max(width / 2, 1) × max(height / 2, 1)
//!   …        down to 1 × 1: the texture's mean colour
//! ```
//!
//! A texel is RGBA8 with sRGB-encoded colour and linear alpha, packed as one `u32` (R in the low byte);
//! `gpu_scene::gpu_textures` lays the textures out so and writes each one's `GpuTexture`.
//! Filtering happens after decoding (linear light), as a GPU's sRGB formats do. Coordinates repeat (the
//! default of OBJ and glTF); (0, 0) is the image's top-left corner, so an OBJ `vt` reads as (u, 1 − v).

use std::path::Path;

use anyhow::{Context as _, Result, bail};
use glam::{Vec2, Vec4};

/// One image level: `width` × `height` packed texels.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<u32>,
}

/// A mipmapped colour texture.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from (a file, or a glTF image's name), for messages.
    pub name: String,
    /// Level 0 first, each half the previous (rounded down, at least 1), down to 1 × 1.
    pub levels: Vec<Level>,
}

/// Largest side accepted (a larger image is an error, said before it is decoded): beyond it, texel
/// coordinates lose precision in `f32` and one image alone would exhaust a storage buffer.
pub const MAX_SIDE: u32 = 16384;

impl Texture {
    /// Reads and decodes the image file at `path` (PNG, JPEG, TGA, BMP or Radiance HDR).
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).with_context(|| format!("cannot read texture {}", path.display()))?;
        Self::decode(&bytes, &path.display().to_string())
    }

    /// Decodes an image held in memory; `name` says where it came from in errors.
    pub fn decode(bytes: &[u8], name: &str) -> Result<Self> {
        Self::decode_as(bytes, name, false)
    }

    /// Decodes a cut-out mask: its alpha where the image has an alpha channel, else its first channel
    /// taken as alpha (a grey mask, as MTL's `map_d` usually is).
    pub fn decode_mask(bytes: &[u8], name: &str) -> Result<Self> {
        Self::decode_as(bytes, name, true)
    }

    fn decode_as(bytes: &[u8], name: &str, mask: bool) -> Result<Self> {
        let unreadable = || format!("texture {name} is not a readable image");
        let reader = || -> Result<image::ImageReader<std::io::Cursor<&[u8]>>> {
            let mut reader =
                image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format().with_context(unreadable)?;
            // TGA has no signature to guess it by: its name's extension says it.
            if reader.format().is_none() {
                reader.set_format(image::ImageFormat::from_path(name).with_context(unreadable)?);
            }
            Ok(reader)
        };
        // A header claiming a huge image is refused, with its size, before anything is allocated for it.
        let (width, height) = reader()?.into_dimensions().with_context(unreadable)?;
        if width > MAX_SIDE || height > MAX_SIDE {
            bail!("texture {name} is {width} × {height} texels: larger than {MAX_SIDE} on a side");
        }
        if width == 0 || height == 0 {
            bail!("texture {name} is {width} × {height}: it has no texels");
        }
        // The decoder may allocate what the image needs (at most four f32 channels a texel), not its own
        // default of 512 MiB, which refused a 12 000² RGBA PNG as "Memory limit exceeded". What the device
        // holds is checked once every texture is read (`renderer::check_textures`).
        let mut limits = image::Limits::default();
        (limits.max_image_width, limits.max_image_height) = (Some(MAX_SIDE), Some(MAX_SIDE));
        limits.max_alloc = Some(16 * width as u64 * height as u64 + (1 << 20));
        let mut reader = reader()?;
        reader.limits(limits);
        let image = reader.decode().with_context(unreadable)?;
        let (width, height) = (image.width(), image.height());
        let from_red = mask && !image.color().has_alpha();
        let rgba = image.to_rgba8();
        let texel = |[r, g, b, a]: [u8; 4]| u32::from_le_bytes([r, g, b, if from_red { r } else { a }]);
        let texels = rgba.pixels().map(|p| texel(p.0)).collect();
        Ok(Self::from_level(name, Level { width, height, texels }))
    }

    /// A texture from its full-resolution level; the smaller levels are box-filtered in linear light.
    pub fn from_level(name: &str, level: Level) -> Self {
        let mut levels = vec![level];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            levels.push(downsample(last));
        }
        Self { name: name.to_owned(), levels }
    }

    pub fn width(&self) -> u32 {
        self.levels[0].width
    }

    pub fn height(&self) -> u32 {
        self.levels[0].height
    }

    /// Texels of every level.
    pub fn texel_count(&self) -> usize {
        self.levels.iter().map(|l| l.texels.len()).sum()
    }

    /// The mean colour and alpha over the whole texture (its 1 × 1 level), linear.
    pub fn mean(&self) -> Vec4 {
        decode(self.levels.last().expect("a texture has levels").texels[0])
    }

    /// The texels (of its full-resolution level) that a triangle with texture coordinates `uv` covers.
    pub fn footprint(&self, uv: &[Vec2; 3]) -> f32 {
        let size = Vec2::new(self.width() as f32, self.height() as f32);
        0.5 * ((uv[1] - uv[0]) * size).perp_dot((uv[2] - uv[0]) * size).abs()
    }

    /// The mean colour and alpha over a triangle with texture coordinates `uv`: the mean of 16 points spread
    /// evenly over it (the centroids of its 4 × 4 subdivision), read at the level of detail where each
    /// covers its sixteenth of the footprint, so that together they cover it.
    pub fn mean_over(&self, uv: &[Vec2; 3]) -> Vec4 {
        const N: usize = 4;
        let lod = 0.5 * (self.footprint(uv) / (N * N) as f32).max(1.0).log2();
        let mut sum = Vec4::ZERO;
        for centroid in super::subdivision_centroids(N) {
            sum += self.sample(super::at_barycentric(uv, centroid), lod);
        }
        sum / (N * N) as f32
    }

    /// Linear colour and alpha at `uv` (repeating) on level of detail `lod` (0: full resolution; between
    /// levels, both are blended): bilinear within a level, as `glsl/texture.glsl` samples.
    pub fn sample(&self, uv: Vec2, lod: f32) -> Vec4 {
        let top = (self.levels.len() - 1) as f32;
        let lod = if lod.is_finite() { lod.clamp(0.0, top) } else { 0.0 };
        let lower = lod.floor();
        let a = bilinear(&self.levels[lower as usize], uv);
        if lod == lower {
            return a;
        }
        a.lerp(bilinear(&self.levels[lower as usize + 1], uv), lod - lower)
    }
}

/// Bilinear filtering of `level` at `uv`, coordinates repeating; texel centres at half-integers.
fn bilinear(level: &Level, uv: Vec2) -> Vec4 {
    let (w, h) = (level.width as i64, level.height as i64);
    let wrapped = uv - uv.floor();
    let x = wrapped.x * w as f32 - 0.5;
    let y = wrapped.y * h as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |i: i64, j: i64| decode(level.texels[(j.rem_euclid(h) * w + i.rem_euclid(w)) as usize]);
    let (i, j) = (x0 as i64, y0 as i64);
    let top = at(i, j).lerp(at(i + 1, j), fx);
    let bottom = at(i, j + 1).lerp(at(i + 1, j + 1), fx);
    top.lerp(bottom, fy)
}

/// The next level: each texel the mean of the 2 × 2 (or fewer, at an odd edge) texels it covers.
fn downsample(level: &Level) -> Level {
    let (width, height) = ((level.width / 2).max(1), (level.height / 2).max(1));
    let mut texels = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let mut sum = Vec4::ZERO;
            let mut n = 0.0;
            for sy in (2 * y)..(2 * y + 2).min(level.height) {
                for sx in (2 * x)..(2 * x + 2).min(level.width) {
                    sum += decode(level.texels[(sy * level.width + sx) as usize]);
                    n += 1.0;
                }
            }
            texels.push(encode(sum / n));
        }
    }
    Level { width, height, texels }
}

/// The sRGB transfer function's inverse (IEC 61966-2-1).
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.0031308 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// A packed texel as linear colour and alpha.
pub fn decode(texel: u32) -> Vec4 {
    let [r, g, b, a] = texel.to_le_bytes().map(|v| v as f32 / 255.0);
    Vec4::new(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b), a)
}

/// Linear colour and alpha packed as a texel (rounded to nearest).
pub fn encode(c: Vec4) -> u32 {
    let byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let [r, g, b] = [c.x, c.y, c.z].map(|v| byte(linear_to_srgb(v.clamp(0.0, 1.0))));
    u32::from_le_bytes([r, g, b, byte(c.w)])
}

/// Bytes the textures take on the GPU.
pub fn gpu_bytes(textures: &[Texture]) -> u64 {
    4 * textures.iter().map(|t| t.texel_count() as u64).sum::<u64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(width: u32, height: u32, texels: &[[u8; 4]]) -> Texture {
        Texture::from_level(
            "t",
            Level { width, height, texels: texels.iter().map(|&t| u32::from_le_bytes(t)).collect() },
        )
    }

    /// TGA has no signature: it is read by its name's extension (Crytek Sponza's textures are TGA).
    #[test]
    fn a_tga_is_read_by_its_extension() {
        let image = image::RgbaImage::from_fn(2, 2, |x, y| image::Rgba([x as u8 * 200, y as u8 * 100, 7, 255]));
        let mut bytes = std::io::Cursor::new(Vec::new());
        image.write_to(&mut bytes, image::ImageFormat::Tga).unwrap();
        let t = Texture::decode(bytes.get_ref(), "bricks.tga").unwrap();
        assert_eq!(t.levels[0].texels[1], u32::from_le_bytes([200, 0, 7, 255]));
        let e = Texture::decode(bytes.get_ref(), "bricks.data").unwrap_err();
        assert!(format!("{e:#}").contains("bricks.data is not a readable image"), "{e:#}");
    }

    #[test]
    fn srgb_round_trips_every_byte() {
        for v in 0..=255u8 {
            let t = u32::from_le_bytes([v, v, v, v]);
            assert_eq!(encode(decode(t)), t, "byte {v}");
        }
        // Mid-grey in sRGB is about a fifth in linear light.
        assert!((decode(u32::from_le_bytes([128, 128, 128, 255])).x - 0.2158).abs() < 1e-3);
    }

    #[test]
    fn levels_halve_down_to_the_mean() {
        // 3 × 2: odd width; level 1 is 1 × 1 and averages the 2 × 2 it covers (the third column dropped).
        let t = texture(
            3,
            2,
            &[[255, 0, 0, 255], [0, 0, 0, 255], [9, 9, 9, 255], [255, 0, 0, 255], [0, 0, 0, 255], [9, 9, 9, 255]],
        );
        assert_eq!(t.levels.len(), 2);
        assert_eq!((t.levels[1].width, t.levels[1].height), (1, 1));
        assert!((t.mean().x - 0.5).abs() < 0.01, "{}", t.mean());
        let even = texture(4, 1, &[[255, 255, 255, 255], [0, 0, 0, 0], [255, 255, 255, 255], [0, 0, 0, 0]]);
        assert_eq!(even.levels.iter().map(|l| l.width).collect::<Vec<_>>(), [4, 2, 1]);
        assert!((even.mean() - Vec4::splat(0.5)).abs().max_element() < 0.01);
    }

    #[test]
    fn sampling_is_bilinear_between_centres_and_repeats() {
        let (black, white) = ([0, 0, 0, 255], [255, 255, 255, 255]);
        let t = texture(2, 1, &[black, white]);
        // Texel centres at u = 0.25 and 0.75; halfway between them, half; at u = 0 halfway across the seam.
        assert!(t.sample(Vec2::new(0.25, 0.5), 0.0).x.abs() < 1e-6);
        assert!((t.sample(Vec2::new(0.75, 0.5), 0.0).x - 1.0).abs() < 1e-6);
        assert!((t.sample(Vec2::new(0.5, 0.5), 0.0).x - 0.5).abs() < 1e-6);
        assert!((t.sample(Vec2::new(0.0, 0.5), 0.0).x - 0.5).abs() < 1e-6);
        assert_eq!(t.sample(Vec2::new(1.25, 7.5), 0.0), t.sample(Vec2::new(0.25, 0.5), 0.0));
        assert_eq!(t.sample(Vec2::new(-0.75, 0.5), 0.0), t.sample(Vec2::new(0.25, 0.5), 0.0));
        // Level 1 is the mean; lod 0.5 blends the two levels; past the last level, the last.
        assert!((t.sample(Vec2::new(0.25, 0.5), 1.0).x - 0.5).abs() < 0.01);
        assert!((t.sample(Vec2::new(0.25, 0.5), 0.5).x - 0.25).abs() < 0.01);
        assert_eq!(t.sample(Vec2::new(0.25, 0.5), 9.0), t.sample(Vec2::new(0.25, 0.5), 1.0));
    }

    #[test]
    fn a_corrupt_image_is_an_error_naming_it() {
        let e = Texture::decode(b"\x89PNG\r\n\x1a\nnot really", "wood.png").unwrap_err();
        assert!(format!("{e:#}").contains("texture wood.png is not a readable image"), "{e:#}");
    }
}
