//! An environment-map sky: the radiance of every ray that leaves the scene, by direction, from an
//! equirectangular (latitude–longitude) HDR image (OpenEXR or Radiance HDR). The constant background is the
//! other kind of sky (`--background`).
//!
//! Directions map to the image as Mitsuba 3's `envmap` and most HDRI tools map them, with +y up:
//!
//! ```text
//!   u = atan2(d.x, −d.z) / 2π  (wrapped into [0, 1))    v = acos(d.y) / π
//!
//!   u:  0 ........ 0.25 ........ 0.5 ........ 0.75 ........ 1
//!      −z           +x           +z           −x           −z      v = 0: row 0, the zenith (+y)
//!                                                                  v = 1: the last row, the nadir (−y)
//! ```
//!
//! Each texel is the mean radiance of its cell, a band of latitude `π / height` by `2π / width` of
//! longitude; between texel centres the radiance is bilinear (wrapping in u, clamped in v), as the oracle,
//! the host and `glsl/sky.glsl` read it. Smaller levels (2 × 2 box means down to 1 × 1) serve the sensors,
//! whose texels each cover a solid angle many map texels wide: they read the level whose texels are about as
//! large ([`SkyMap::lod`]).
//!
//! `rotation_deg` turns the map about +y (counter-clockwise seen from above, as Mitsuba's
//! `rotate(y, angle)`): what the map shows at direction m appears at `R_y(angle)·m`.
//!
//! The oracle samples directions in proportion to the map's luminance ([`SkyMap::sample`]): a bright sun in
//! the map is found by its own samples, not by luck.

use std::f32::consts::PI;
use std::path::Path;

use anyhow::{Context as _, Result, bail, ensure};
use glam::{Vec2, Vec3};

use rayon::prelude::*;

use super::texture::MAX_SIDE;
use super::{Camera, ImageSize};

/// Relative luminance (Rec. 709), for the sampling density.
const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// One level of the map: `width` × `height` linear RGB texels, row 0 the zenith's band.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyLevel {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
}

/// An equirectangular environment map with its levels and its sampling distribution.
#[derive(Clone, Debug)]
pub struct SkyMap {
    /// The file it came from, for messages and the scene file.
    pub name: String,
    /// The factor its texels were multiplied by (`[sky] strength`, `--sky-strength`).
    pub strength: f32,
    /// Its turn about +y in degrees (`[sky] rotation_deg`, `--sky-rotation`); `turn` holds its sine and
    /// cosine.
    pub rotation_deg: f32,
    turn: (f32, f32),
    /// Level 0 first, each half the previous (rounded down, at least 1) down to 1 × 1.
    pub levels: Vec<SkyLevel>,
    /// The sun taken out of the map ([`SkyMap::without_sun`]), which the scene draws as its sun.
    pub taken_sun: Option<super::Sun>,
    /// Cumulative sums for sampling: each row's total (`marginal`), and each row's texels (`conditional`).
    marginal: Vec<f32>,
    conditional: Vec<f32>,
}

impl SkyMap {
    /// Reads the map at `path` (`.exr`; anything else is decoded by the image crate, e.g. Radiance `.hdr`)
    /// and scales it by `strength`.
    pub fn load(path: &Path, strength: f32) -> Result<Self> {
        let bytes = std::fs::read(path).with_context(|| format!("cannot read sky map {}", path.display()))?;
        let name = path.display().to_string();
        let (width, height, texels) = decode(&bytes, &name)?;
        Self::new(&name, SkyLevel { width, height, texels }, strength)
    }

    /// A map of level 0 `level` (every texel finite and non-negative, else an error naming the first that
    /// is not) scaled by `strength`.
    pub fn new(name: &str, mut level: SkyLevel, strength: f32) -> Result<Self> {
        ensure!(
            strength.is_finite() && strength >= 0.0,
            "sky map {name}: strength must be a finite number ≥ 0, got {strength}"
        );
        ensure!(level.width >= 1 && level.height >= 1, "sky map {name} has no texels");
        ensure!(level.texels.len() == (level.width * level.height) as usize, "sky map {name}: wrong texel count");
        if let Some(i) = level.texels.iter().position(|t| !(t.is_finite() && t.min_element() >= 0.0)) {
            let (x, y) = (i as u32 % level.width, i as u32 / level.width);
            bail!("sky map {name}: texel ({x}, {y}) is {}, not a radiance (finite, ≥ 0)", level.texels[i]);
        }
        for t in &mut level.texels {
            *t *= strength;
        }
        let mut levels = vec![level];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            levels.push(downsample(last));
        }
        let (marginal, conditional) = distribution(&levels[0]);
        let turn = (0.0, 1.0);
        Ok(Self {
            name: name.to_owned(),
            strength,
            rotation_deg: 0.0,
            turn,
            levels,
            taken_sun: None,
            marginal,
            conditional,
        })
    }

    /// The map turned about +y by `degrees` (module docs).
    pub fn turned(mut self, degrees: f32) -> Result<Self> {
        ensure!(
            degrees.is_finite(),
            "sky map {}: rotation must be a finite number of degrees, got {degrees}",
            self.name
        );
        self.rotation_deg = degrees;
        self.turn = degrees.to_radians().sin_cos();
        Ok(self)
    }

    /// The map's direction for the world direction `d`: `R_y(−angle)·d`.
    fn to_map(&self, d: Vec3) -> Vec3 {
        let (sin, cos) = self.turn;
        Vec3::new(cos * d.x - sin * d.z, d.y, sin * d.x + cos * d.z)
    }

    /// The world direction for the map's direction `m`: `R_y(angle)·m`.
    pub(super) fn to_world(&self, m: Vec3) -> Vec3 {
        let (sin, cos) = self.turn;
        Vec3::new(cos * m.x + sin * m.z, m.y, -sin * m.x + cos * m.z)
    }

    pub fn width(&self) -> u32 {
        self.levels[0].width
    }

    pub fn height(&self) -> u32 {
        self.levels[0].height
    }

    /// The mean radiance over the map's texels (its 1 × 1 level).
    pub fn mean(&self) -> Vec3 {
        self.levels.last().expect("a map has levels").texels[0]
    }

    /// Texels of every level.
    pub fn texel_count(&self) -> usize {
        self.levels.iter().map(|l| l.texels.len()).sum()
    }

    /// The radiance arriving from direction `d` (unit), bilinear on level 0.
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        bilinear(&self.levels[0], direction_to_uv(self.to_map(d)))
    }

    /// The radiance from `d` on level of detail `lod` (blending the two levels around it), as
    /// `glsl/sky.glsl`'s `sky_radiance` reads it.
    pub fn radiance_lod(&self, d: Vec3, lod: f32) -> Vec3 {
        let top = (self.levels.len() - 1) as f32;
        let lod = if lod.is_finite() { lod.clamp(0.0, top) } else { 0.0 };
        let lower = lod.floor();
        let uv = direction_to_uv(self.to_map(d));
        let a = bilinear(&self.levels[lower as usize], uv);
        if lod == lower { a } else { a.lerp(bilinear(&self.levels[lower as usize + 1], uv), lod - lower) }
    }

    /// The level of detail whose texels at the horizon cover about `solid_angle` (steradians): a level-0
    /// texel there covers `(2π / width)(π / height)`, and each level four times as much.
    pub fn lod(&self, solid_angle: f32) -> f32 {
        let texel = 2.0 * PI * PI / (self.width() * self.height()) as f32;
        (0.5 * (solid_angle / texel).log2()).max(0.0)
    }

    /// The sky each pixel of an image of `size` shows through `camera` where no surface is in front of it:
    /// the mean over a `side` × `side` grid of points in the pixel's square (its centre for `side` 1).
    pub fn pixels(&self, camera: &Camera, size: ImageSize, side: u32) -> Vec<Vec3> {
        let width = size.width as usize;
        (0..width * size.height as usize)
            .into_par_iter()
            .map(|i| {
                let (x, y) = ((i % width) as f32, (i / width) as f32);
                let mut sum = Vec3::ZERO;
                for j in 0..side {
                    for k in 0..side {
                        let (u, v) = ((k as f32 + 0.5) / side as f32, (j as f32 + 0.5) / side as f32);
                        sum += self.radiance(camera.ray(x + u, y + v, size.width, size.height).dir);
                    }
                }
                sum / (side * side) as f32
            })
            .collect()
    }

    /// Whether the map can be sampled: some texel is bright.
    pub fn can_sample(&self) -> bool {
        self.marginal.last().is_some_and(|&t| t > 0.0)
    }

    /// A direction drawn in proportion to the map's luminance (as a density over the sphere), from the
    /// uniform pair `u`, and its density per steradian; `None` where the map is black or the cell degenerate.
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let total = *self.marginal.last()?;
        if total <= 0.0 {
            return None;
        }
        let (w, h) = (self.width() as usize, self.height() as usize);
        let (row, fy) = pick(&self.marginal, u.y * total);
        let cdf = &self.conditional[row * w..(row + 1) * w];
        let (column, fx) = pick(cdf, u.x * cdf[w - 1]);
        let uv = Vec2::new((column as f32 + fx) / w as f32, (row as f32 + fy) / h as f32);
        let d = self.to_world(uv_to_direction(uv));
        let pdf = self.pdf(d);
        (pdf > 0.0).then_some((d, pdf))
    }

    /// The density per steradian with which [`SkyMap::sample`] draws `d`: the cell's share of the total,
    /// uniform over the cell in (u, v), over the cell's `dω = 2π² sinθ du dv`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        let Some(&total) = self.marginal.last().filter(|&&t| t > 0.0) else { return 0.0 };
        let (w, h) = (self.width() as usize, self.height() as usize);
        let d = self.to_map(d);
        let uv = direction_to_uv(d);
        let column = ((uv.x * w as f32) as usize).min(w - 1);
        let row = ((uv.y * h as f32) as usize).min(h - 1);
        let cdf = &self.conditional[row * w..(row + 1) * w];
        let cell = cdf[column] - if column > 0 { cdf[column - 1] } else { 0.0 };
        let row_share = cdf[w - 1] / total;
        // From x and z, not √(1 − y²): near a pole y rounds to ±1.
        let sin_theta = Vec2::new(d.x, d.z).length();
        if sin_theta <= 0.0 || cdf[w - 1] <= 0.0 {
            return 0.0;
        }
        row_share * (cell / cdf[w - 1]) * (w * h) as f32 / (2.0 * PI * PI * sin_theta)
    }
}

/// Texture coordinates of the unit direction `d` (module docs).
pub fn direction_to_uv(d: Vec3) -> Vec2 {
    let u = d.x.atan2(-d.z) / (2.0 * PI);
    Vec2::new(u - u.floor(), d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// The unit direction at texture coordinates `uv` (module docs).
pub fn uv_to_direction(uv: Vec2) -> Vec3 {
    let (phi, theta) = (2.0 * PI * uv.x, PI * uv.y);
    let (sin_theta, cos_theta) = theta.sin_cos();
    Vec3::new(phi.sin() * sin_theta, cos_theta, -phi.cos() * sin_theta)
}

/// Bilinear filtering of `level` at `uv`: texel centres at half-integers, u wrapping, v clamped.
fn bilinear(level: &SkyLevel, uv: Vec2) -> Vec3 {
    let (w, h) = (level.width as i64, level.height as i64);
    let x = (uv.x - uv.x.floor()) * w as f32 - 0.5;
    let y = (uv.y.clamp(0.0, 1.0) * h as f32 - 0.5).clamp(0.0, (h - 1) as f32);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |i: i64, j: i64| level.texels[(j.min(h - 1) * w + i.rem_euclid(w)) as usize];
    let (i, j) = (x0 as i64, y0 as i64);
    let top = at(i, j).lerp(at(i + 1, j), fx);
    let bottom = at(i, j + 1).lerp(at(i + 1, j + 1), fx);
    top.lerp(bottom, fy)
}

/// The next level: each texel the mean of the 2 × 2 (or fewer, at an odd edge) texels it covers.
fn downsample(level: &SkyLevel) -> SkyLevel {
    let (width, height) = ((level.width / 2).max(1), (level.height / 2).max(1));
    let mut texels = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let (mut sum, mut n) = (Vec3::ZERO, 0.0);
            for sy in (2 * y)..(2 * y + 2).min(level.height) {
                for sx in (2 * x)..(2 * x + 2).min(level.width) {
                    sum += level.texels[(sy * level.width + sx) as usize];
                    n += 1.0;
                }
            }
            texels.push(sum / n);
        }
    }
    SkyLevel { width, height, texels }
}

/// The sampling distribution's cumulative sums: a cell's weight is the brightest luminance among the texels
/// its bilinear radiance mixes (its own and its eight neighbours), times its band's `sinθ` (its solid
/// angle). The neighbours make the density positive wherever the radiance is, so the samples miss nothing.
fn distribution(level: &SkyLevel) -> (Vec<f32>, Vec<f32>) {
    let (w, h) = (level.width as i64, level.height as i64);
    let lum = |i: i64, j: i64| level.texels[(j.clamp(0, h - 1) * w + i.rem_euclid(w)) as usize].dot(LUMINANCE);
    let mut conditional = Vec::with_capacity((w * h) as usize);
    let mut marginal = Vec::with_capacity(h as usize);
    let mut total = 0.0f64;
    for j in 0..h {
        let sin_theta = (PI * (j as f32 + 0.5) / h as f32).sin();
        let mut row = 0.0f64;
        for i in 0..w {
            let brightest =
                (-1..=1).flat_map(|dj| (-1..=1).map(move |di| (di, dj))).map(|(di, dj)| lum(i + di, j + dj));
            row += (brightest.fold(0.0, f32::max) * sin_theta) as f64;
            conditional.push(row as f32);
        }
        total += row;
        marginal.push(total as f32);
    }
    (marginal, conditional)
}

/// The index whose cumulative interval `[cdf[i−1], cdf[i])` holds `x`, and where in it `x` lies (inside
/// (0, 1): never on a cell's edge, so never on a pole, where the density is undefined).
fn pick(cdf: &[f32], x: f32) -> (usize, f32) {
    let i = cdf.partition_point(|&c| c <= x).min(cdf.len() - 1);
    let lo = if i > 0 { cdf[i - 1] } else { 0.0 };
    let width = cdf[i] - lo;
    (i, if width > 0.0 { ((x - lo) / width).clamp(1e-6, 1.0 - 1e-6) } else { 0.5 })
}

/// Decodes an HDR image held in memory: OpenEXR (its first layer's R, G, B) or, by its content, any format
/// the image crate reads (Radiance HDR). Sides above [`MAX_SIDE`] are refused before texels are allocated.
pub fn decode(bytes: &[u8], name: &str) -> Result<(u32, u32, Vec<Vec3>)> {
    if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        return decode_exr(bytes, name);
    }
    let unreadable = || format!("sky map {name} is not a readable HDR image (OpenEXR or Radiance HDR)");
    let mut reader =
        image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format().with_context(unreadable)?;
    let mut limits = image::Limits::default();
    (limits.max_image_width, limits.max_image_height) = (Some(MAX_SIDE), Some(MAX_SIDE));
    reader.limits(limits);
    let image = reader.decode().with_context(unreadable)?;
    let (width, height) = (image.width(), image.height());
    let texels = image.to_rgb32f().pixels().map(|p| Vec3::from(p.0)).collect();
    Ok((width, height, texels))
}

fn decode_exr(bytes: &[u8], name: &str) -> Result<(u32, u32, Vec<Vec3>)> {
    use exr::prelude::*;
    /// Texels, or `None` where the header claims more than [`MAX_SIDE`] (nothing allocated).
    struct Texels {
        size: (usize, usize),
        texels: Option<Vec<Vec3>>,
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, _| {
                let fits = size.width() <= MAX_SIDE as usize && size.height() <= MAX_SIDE as usize;
                let texels = fits.then(|| vec![Vec3::ZERO; size.width() * size.height()]);
                Texels { size: (size.width(), size.height()), texels }
            },
            |t: &mut Texels, at, (r, g, b, _a): (f32, f32, f32, f32)| {
                let width = t.size.0;
                if let Some(texels) = &mut t.texels {
                    texels[at.y() * width + at.x()] = Vec3::new(r, g, b);
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| anyhow::anyhow!("sky map {name} is not a readable OpenEXR image: {e}"))?;
    let Texels { size: (width, height), texels } = image.layer_data.channel_data.pixels;
    let Some(texels) = texels else {
        bail!("sky map {name} is {width} × {height}: larger than {MAX_SIDE} on a side");
    };
    Ok((width as u32, height as u32, texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(width: u32, height: u32, f: impl Fn(Vec3) -> Vec3) -> SkyMap {
        let mut texels = Vec::new();
        for y in 0..height {
            for x in 0..width {
                let uv = Vec2::new((x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / height as f32);
                texels.push(f(uv_to_direction(uv)));
            }
        }
        SkyMap::new("test", SkyLevel { width, height, texels }, 1.0).unwrap()
    }

    #[test]
    fn directions_and_coordinates_round_trip_and_follow_the_convention() {
        for d in [Vec3::X, -Vec3::X, Vec3::Z, -Vec3::Z, Vec3::new(0.3, 0.5, -0.8).normalize()] {
            assert!((uv_to_direction(direction_to_uv(d)) - d).length() < 1e-5, "{d}");
        }
        assert!((direction_to_uv(Vec3::X) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((direction_to_uv(Vec3::Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!(direction_to_uv(Vec3::Y).y.abs() < 1e-6 && (direction_to_uv(-Vec3::Y).y - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_texel_centre_reads_its_texel_and_u_wraps_across_the_seam() {
        let texels: Vec<Vec3> = (0..8).map(|i| Vec3::splat(i as f32)).collect();
        let sky = SkyMap::new("t", SkyLevel { width: 4, height: 2, texels }, 2.0).unwrap();
        assert_eq!(sky.radiance(uv_to_direction(Vec2::new(0.375, 0.25))), Vec3::splat(2.0 * 1.0));
        // Halfway between the last column and the first, on row 1 (texels 7 and 4).
        assert!((sky.radiance(uv_to_direction(Vec2::new(0.999_99, 0.75))).x - 2.0 * 5.5).abs() < 1e-3);
        assert_eq!(sky.levels.len(), 3);
        assert_eq!(sky.levels[2].texels[0], Vec3::splat(2.0 * 3.5));
    }

    #[test]
    fn the_sampling_density_integrates_to_one_and_matches_the_histogram_of_samples() {
        // A dim sky with a bright blob: most samples must land in the blob.
        let blob = Vec3::new(0.5, 0.6, -0.6).normalize();
        let sky = map(64, 32, |d| Vec3::splat(0.1 + 50.0 * d.dot(blob).max(0.0).powi(40)));
        // ∫ p dω over the sphere by a fine midpoint rule in (u, v).
        let n = 512;
        let mut integral = 0.0f64;
        for j in 0..n {
            for i in 0..2 * n {
                let uv = Vec2::new((i as f32 + 0.5) / (2 * n) as f32, (j as f32 + 0.5) / n as f32);
                let d = uv_to_direction(uv);
                let domega = 2.0 * PI * PI * (PI * uv.y).sin() / (2 * n * n) as f32;
                integral += (sky.pdf(d) * domega) as f64;
            }
        }
        assert!((integral - 1.0).abs() < 2e-3, "∫ pdf = {integral}");
        // Samples: each returned density is the pdf of its direction, and the estimate of ∫ L dω from them
        // matches the midpoint rule's.
        let mut estimate = Vec3::ZERO;
        let count = 1 << 14;
        for k in 0..count {
            let u =
                Vec2::new((k as f32 + 0.5) / count as f32, ((k as u64 * 40503) % count as u64) as f32 / count as f32);
            let (d, pdf) = sky.sample(u).unwrap();
            assert!((pdf - sky.pdf(d)).abs() <= 1e-3 * pdf, "{pdf} vs {}", sky.pdf(d));
            estimate += sky.radiance(d) / pdf;
        }
        estimate /= count as f32;
        let mut exact = Vec3::ZERO;
        for j in 0..n {
            for i in 0..2 * n {
                let uv = Vec2::new((i as f32 + 0.5) / (2 * n) as f32, (j as f32 + 0.5) / n as f32);
                exact += sky.radiance(uv_to_direction(uv)) * 2.0 * PI * PI * (PI * uv.y).sin() / (2 * n * n) as f32;
            }
        }
        assert!((estimate.x / exact.x - 1.0).abs() < 0.01, "{estimate} vs {exact}");
    }

    /// Turned by 90°, what the map shows towards −z appears towards −x (R_y(90°) takes −z to −x), and
    /// samples and densities turn with it.
    #[test]
    fn a_turned_map_turns_its_radiance_and_its_samples() {
        let blob = -Vec3::Z;
        let unturned = map(64, 32, |d| Vec3::splat(0.1 + 50.0 * d.dot(blob).max(0.0).powi(40)));
        let sky = unturned.clone().turned(90.0).unwrap();
        let (peak, turned) = (unturned.radiance(-Vec3::Z), sky.radiance(-Vec3::X));
        assert!(peak.x > 40.0 && (turned - peak).abs().max_element() < 1e-3 * peak.x, "{turned} vs {peak}");
        assert!(sky.radiance(-Vec3::Z).x < 0.2);
        let mut towards = 0;
        for k in 0..256 {
            let u = Vec2::new((k as f32 + 0.5) / 256.0, ((k * 97) % 256) as f32 / 256.0);
            let (d, pdf) = sky.sample(u).unwrap();
            assert!((pdf - sky.pdf(d)).abs() <= 1e-3 * pdf);
            towards += (d.dot(-Vec3::X) > 0.7) as u32;
        }
        assert!(towards > 200, "{towards} of 256 samples towards the turned blob");
        assert!(map(4, 2, |_| Vec3::ONE).turned(f32::NAN).is_err());
    }

    #[test]
    fn bad_texels_and_strengths_are_errors_that_say_where() {
        let level = |t: Vec3| SkyLevel { width: 2, height: 1, texels: vec![Vec3::ONE, t] };
        let e = SkyMap::new("s.exr", level(Vec3::new(1.0, f32::NAN, 0.0)), 1.0).unwrap_err().to_string();
        assert!(e.contains("s.exr") && e.contains("(1, 0)"), "{e}");
        assert!(SkyMap::new("s.exr", level(-Vec3::ONE), 1.0).is_err());
        assert!(SkyMap::new("s.exr", level(Vec3::ONE), -1.0).is_err());
        let e = decode(b"not an image", "x.hdr").unwrap_err().to_string();
        assert!(e.contains("x.hdr"), "{e}");
    }

    #[test]
    fn a_black_map_is_not_sampled() {
        let sky = map(8, 4, |_| Vec3::ZERO);
        assert!(!sky.can_sample() && sky.sample(Vec2::splat(0.5)).is_none() && sky.pdf(Vec3::Y) == 0.0);
    }
}
