//! Lightmaps (`sensorlight bake`): the light at every texel of a second UV set, stored as irradiance over π
//! so that a Lambertian surface shows `albedo × lightmap` (docs/DESIGN.md §14). The renderer senses the
//! texels' points as it senses pixels (`Renderer::sense_points`); this module, on the CPU, knows no GPU
//! pass: the unwrap ([`unwrap`]), which point each texel stands for ([`texels`]), the gutter's fill
//! ([`Atlas::dilate`]), the glTF binary ([`glb`]) and the view an engine shows of the baked scene
//! ([`view`]), against which `render`'s image is checked.

pub mod glb;
pub mod texels;
pub mod unwrap;
pub mod view;

use glam::{Vec2, Vec3, Vec4};

/// The baked light: per page, texels row by row from the top, irradiance / π (linear, the unit of the
/// scene's `Ke`); `valid` says which texels hold light (a point sensed, or filled from one).
#[derive(Clone, Debug)]
pub struct Atlas {
    pub width: u32,
    pub height: u32,
    pub pages: u32,
    pub texels: Vec<Vec3>,
    pub valid: Vec<bool>,
}

/// How many rings of texels around the charts [`Atlas::dilate`] fills: the gutter's two and a margin, so
/// that every texel a bilinear or first-mip fetch at a chart's border reads holds the chart's light.
pub const DILATE_RINGS: u32 = 4;

impl Atlas {
    /// An atlas of `width` × `height` × `pages` with the light `values` where `valid`.
    pub fn new((width, height, pages): (u32, u32, u32), texels: Vec<Vec3>, valid: Vec<bool>) -> Self {
        assert_eq!(texels.len(), width as usize * height as usize * pages as usize);
        assert_eq!(texels.len(), valid.len());
        Self { width, height, pages, texels, valid }
    }

    /// Fills texels without light from their valid neighbours (the mean of the 8 around), ring after ring,
    /// [`DILATE_RINGS`] times: the gutter and the buried texels (`texels`), so that filtering at a chart's
    /// border never reads black.
    pub fn dilate(&mut self) {
        let (w, h) = (self.width as i64, self.height as i64);
        let page = (w * h) as usize;
        for _ in 0..DILATE_RINGS {
            let mut filled = Vec::new();
            for i in 0..self.texels.len() {
                if self.valid[i] {
                    continue;
                }
                let (base, j) = (i - i % page, (i % page) as i64);
                let (x, y) = (j % w, j / w);
                let (mut sum, mut n) = (Vec3::ZERO, 0);
                for (dx, dy) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (dx, dy))) {
                    let (nx, ny) = (x + dx, y + dy);
                    if (0..w).contains(&nx) && (0..h).contains(&ny) {
                        let k = base + (ny * w + nx) as usize;
                        if self.valid[k] {
                            sum += self.texels[k];
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    filled.push((i, sum / n as f32));
                }
            }
            if filled.is_empty() {
                break;
            }
            for (i, v) in filled {
                self.texels[i] = v;
                self.valid[i] = true;
            }
        }
    }

    /// The light at `uv` of `page` as an engine's bilinear filter reads it: texel centres at
    /// (i + ½) / width, clamped at the page's edges.
    pub fn bilinear(&self, page: u32, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let p = uv * Vec2::new(w as f32, h as f32) - 0.5;
        let (x0, y0) = (p.x.floor(), p.y.floor());
        let (fx, fy) = (p.x - x0, p.y - y0);
        let base = page as usize * (w * h) as usize;
        let at = |x: i64, y: i64| self.texels[base + (y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize];
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1, y0) * fx;
        let bottom = at(x0, y0 + 1) * (1.0 - fx) + at(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Page `page`'s texels as RGBA (alpha 1 where a texel holds light): for the EXR.
    pub fn page_rgba(&self, page: u32) -> Vec<Vec4> {
        let range = self.page_range(page);
        self.texels[range.clone()].iter().zip(&self.valid[range]).map(|(t, &v)| t.extend(v as u32 as f32)).collect()
    }

    /// Page `page`'s texels.
    pub fn page(&self, page: u32) -> &[Vec3] {
        &self.texels[self.page_range(page)]
    }

    fn page_range(&self, page: u32) -> std::ops::Range<usize> {
        let n = self.width as usize * self.height as usize;
        page as usize * n..(page as usize + 1) * n
    }
}

/// RGBM's range: an 8-bit RGBM texel holds light up to this (irradiance / π, the scene's `Ke` unit).
pub const RGBM_RANGE: f32 = 8.0;

/// Page texels as 8-bit RGBM (`--format rgbm`), linear (no sRGB curve): the light is
/// `rgb × a × RGBM_RANGE`, each byte over 255; `a` is the smallest multiple of 1/255 that keeps `rgb`
/// within 1 (light above the range clipped).
pub fn rgbm(texels: &[Vec3]) -> Vec<u8> {
    texels
        .iter()
        .flat_map(|&t| {
            let t = t.clamp(Vec3::ZERO, Vec3::splat(RGBM_RANGE)) / RGBM_RANGE;
            let m = (t.max_element() * 255.0).ceil().max(1.0) / 255.0;
            let rgb = (t / m * 255.0).round().min(Vec3::splat(255.0));
            [rgb.x as u8, rgb.y as u8, rgb.z as u8, (m * 255.0).round() as u8]
        })
        .collect()
}

/// The light an RGBM texel holds ([`rgbm`]'s inverse, up to rounding).
pub fn from_rgbm(p: [u8; 4]) -> Vec3 {
    Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / 255.0 * (p[3] as f32 / 255.0) * RGBM_RANGE
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilation_fills_the_gutter_from_the_chart() {
        // A 7 × 1 page lit at texel 1 only: dilation carries its light DILATE_RINGS = 4 texels out, to texel 5.
        let mut texels = vec![Vec3::ZERO; 7];
        texels[1] = Vec3::splat(2.0);
        let mut valid = vec![false; 7];
        valid[1] = true;
        let mut atlas = Atlas::new((7, 1, 1), texels, valid);
        atlas.dilate();
        assert!(atlas.valid[..6].iter().all(|&v| v), "{:?}", atlas.valid);
        assert!(!atlas.valid[6], "only {DILATE_RINGS} rings are filled");
        assert!(atlas.texels[..6].iter().all(|&t| t == Vec3::splat(2.0)));
    }

    #[test]
    fn rgbm_round_trips_within_its_precision() {
        for t in [Vec3::ZERO, Vec3::new(0.01, 0.02, 0.005), Vec3::new(1.0, 0.5, 0.25), Vec3::splat(7.9)] {
            let bytes = rgbm(&[t]);
            let back = from_rgbm(bytes[..4].try_into().unwrap());
            // A byte of the mantissa at the texel's own scale: half of 1/255 of its largest channel.
            assert!((back - t).abs().max_element() <= t.max_element() / 255.0 + 1e-6, "{t} → {back}");
        }
        assert_eq!(from_rgbm(rgbm(&[Vec3::splat(100.0)])[..4].try_into().unwrap()), Vec3::splat(RGBM_RANGE));
    }

    #[test]
    fn bilinear_reads_texel_centres_exactly_and_blends_between() {
        let atlas = Atlas::new((2, 1, 1), vec![Vec3::ZERO, Vec3::ONE], vec![true; 2]);
        assert_eq!(atlas.bilinear(0, Vec2::new(0.25, 0.5)), Vec3::ZERO);
        assert_eq!(atlas.bilinear(0, Vec2::new(0.75, 0.5)), Vec3::ONE);
        assert_eq!(atlas.bilinear(0, Vec2::new(0.5, 0.5)), Vec3::splat(0.5));
        assert_eq!(atlas.bilinear(0, Vec2::new(1.0, 0.5)), Vec3::ONE, "clamped at the edge");
    }
}
