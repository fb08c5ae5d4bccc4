//! Which pixels may not be uniform over their square (step 1 of `supersample`): judged from the centres'
//! G-buffer, the light hints and the triangles' footprints, all on the host before any sensor.

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::gbuffer::GBufferData;
use crate::gbuffer::cast::cast_points;
use crate::light::groups::luminance;
use crate::scene::bvh::Bvh;
use crate::scene::{NO_SURFACE, Scene};
use crate::sensors::hints::{self, LightPoint};
use crate::sensors::refine::NORMAL_TOLERANCE_DEG;

/// Two points lie on two layers of one surface (it folds over itself) where the offset between them leaves
/// the first's tangent plane by more than this share of its length (sin 14°, about the normal tolerance).
pub const DEPTH_JUMP: f32 = 0.25;

/// A hard shadow's edge crosses between two neighbouring pixels where the share of a light group's hint
/// points they see differs by at least this (a penumbra under 4 pixels wide); a wider one is smooth at
/// the pixel's scale, and its centre is its mean.
pub const LIGHT_JUMP: f32 = 0.25;

/// The light ends inside a pixel whose R is under this share of a neighbour's on its surface: a linear
/// ramp reaching zero inside the pixel's square leaves its centre under ¼ of the next pixel's.
pub const LIGHT_END: f32 = 0.25;

/// A triangle whose smallest altitude on screen is under this many pixels may fall between pixel centres
/// (a bar, a light seen edge-on): the pixels it touches are supersampled.
pub const THIN_PIXELS: f32 = 1.5;

/// Why a pixel is supersampled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Flags {
    /// Its neighbourhood shows two surfaces, a crease, two layers or an emitter's rim, or a thin triangle
    /// of another surface touches it: kept only where its samples confirm it.
    pub geometry: bool,
    /// A light group's visible share jumps between it and a neighbour on its surface: always kept.
    pub light: bool,
}

impl Flags {
    pub fn any(self) -> bool {
        self.geometry || self.light
    }
}

/// A visible point: what two samples are compared by.
#[derive(Clone, Copy)]
pub(super) struct Point {
    pub(super) surface: u32,
    position: Vec4,
    normal: Vec3,
    emission: Vec3,
}

impl Point {
    pub(super) fn of(g: &GBufferData, i: usize) -> Self {
        let (position, normal, emission) = (g.position[i], g.normal[i].truncate(), g.emission[i].truncate());
        Self { surface: g.surface[i], position, normal, emission }
    }

    /// Whether `self` and `other` are the same surface alike: one id, normals within the refinement's
    /// tolerance, one emission, one layer.
    pub(super) fn alike(&self, other: &Point) -> bool {
        if self.surface != other.surface {
            return false;
        }
        if self.surface == NO_SURFACE {
            return true;
        }
        let offset = (other.position - self.position).truncate();
        self.normal.dot(other.normal) >= NORMAL_TOLERANCE_DEG.to_radians().cos()
            && (self.emission - other.emission).abs().max_element() <= 1e-6 * self.emission.max_element().max(1.0)
            && self.normal.dot(offset).abs() <= DEPTH_JUMP * offset.length()
    }
}

/// Whether sample `s` of `samples` shows pixel `i`'s centre surface of `g` alike.
pub fn same_surface(g: &GBufferData, i: usize, samples: &GBufferData, s: usize) -> bool {
    Point::of(g, i).alike(&Point::of(samples, s))
}

/// Flags each pixel of the centres' G-buffer `g` of `scene`'s image: geometry where a pixel of its 3 × 3
/// neighbourhood is not [`Point::alike`] or a thin triangle of another surface touches it
/// ([`thin_footprints`]); light where a 4-neighbour on its surface sees a group's hint points (`hints`, a
/// mask per pixel, or empty; `bits`: each group's, `hints::group_bits`) in shares [`LIGHT_JUMP`] apart.
pub fn detect(scene: &Scene, g: &GBufferData, hints: &[u64], bits: &[u64]) -> Vec<Flags> {
    let (w, h) = (g.size.width as i64, g.size.height as i64);
    let thin = thin_footprints(scene, g);
    let share = |i: usize| hints::shares(bits, None, hints[i]);
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let centre = Point::of(g, i as usize);
            let neighbours = (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy)));
            let inside = |&(qx, qy): &(i64, i64)| qx >= 0 && qy >= 0 && qx < w && qy < h && (qx, qy) != (x, y);
            let geometry = thin[i as usize]
                || neighbours
                    .clone()
                    .filter(inside)
                    .any(|(qx, qy)| !centre.alike(&Point::of(g, (qy * w + qx) as usize)));
            let light = !hints.is_empty()
                && centre.surface != NO_SURFACE
                && (neighbours.filter(inside).filter(|(qx, qy)| (qx - x).abs() + (qy - y).abs() == 1))
                    .map(|(qx, qy)| (qy * w + qx) as usize)
                    .filter(|&j| g.surface[j] == centre.surface)
                    .any(|j| {
                        let (a, b) = (share(i as usize), share(j));
                        a.iter().zip(&b).any(|(a, b)| *a >= 0.0 && (a - b).abs() >= LIGHT_JUMP)
                    });
            Flags { geometry, light }
        })
        .collect()
}

/// Light that falls between the pixel centres: a streak narrower than a pixel (the light under a door's
/// 1 cm clearance, on the floor beyond it) that no centre's hint sees, or one that only a centre sees. The
/// camera's rays through the pixels' corners (continuous coordinates, `Camera::ray`) meet the scene, their
/// hints are taken as the centres' are (`sensors::hints`, `points` on the lights, a sensor's lift and near
/// distance `offsets`), and a pixel is light-flagged where a corner of its square that shows its centre's
/// surface alike sees some of a group's hint points and its centre none, or the reverse. The door ajar's
/// streak at 80 × 60 was a row of pixels each 50 % to 100 % too dark with direct light.
pub fn light_between_centres(
    scene: &Scene,
    bvh: &Bvh,
    g: &GBufferData,
    (points, offsets): (&[LightPoint], (f32, f32)),
    (centres, bits): (&[u64], &[u64]),
) -> Vec<bool> {
    let (w, h) = (g.size.width as usize, g.size.height as usize);
    let at: Vec<Vec2> = (0..(w + 1) * (h + 1)).map(|i| Vec2::new((i % (w + 1)) as f32, (i / (w + 1)) as f32)).collect();
    let corners = cast_points(scene, bvh, g.size, &at);
    let masks = hints::hints(bvh, points, &corners, offsets.0, offsets.1);
    let lit = |mask: u64| hints::shares(bits, None, mask).map(|s| s > 0.0);
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let centre = Point::of(g, i);
            if centre.surface == NO_SURFACE {
                return false;
            }
            let (x, y) = (i % w, i / w);
            let seen = lit(centres[i]);
            [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)]
                .into_iter()
                .map(|(cx, cy)| cy * (w + 1) + cx)
                .filter(|&c| centre.alike(&Point::of(&corners, c)))
                .any(|c| lit(masks[c]).iter().zip(&seen).take(bits.len()).any(|(a, b)| a != b))
        })
        .collect()
}

/// Where the light ends inside a pixel (a penumbra's end, or a light setting below a surface's horizon),
/// judged after sensing from every pixel's final R `radiance`: light-flags a surface pixel not in `planned`
/// whose R's luminance is under [`LIGHT_END`] of a 4-neighbour's on its surface. Its centre sees
/// little or none of the light while part of its square sees more: a dim pixel, so a large error relative
/// to its own value (most of the small light's error over the whole image before), which the hints' jump
/// misses where the light fades over more than a pixel.
pub fn light_ends(g: &GBufferData, radiance: &[Vec4], planned: &[u32]) -> Vec<Flags> {
    let (w, h) = (g.size.width as i64, g.size.height as i64);
    let luminance = |i: usize| luminance(radiance[i].truncate());
    let mut taken = vec![false; g.surface.len()];
    planned.iter().for_each(|&i| taken[i as usize] = true);
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let centre = i as usize;
            if g.surface[centre] == NO_SURFACE || taken[centre] {
                return Flags::default();
            }
            let light = [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)]
                .into_iter()
                .filter(|&(qx, qy)| qx >= 0 && qy >= 0 && qx < w && qy < h)
                .map(|(qx, qy)| (qy * w + qx) as usize)
                .filter(|&j| g.surface[j] == g.surface[centre])
                .any(|j| luminance(centre) < LIGHT_END * luminance(j));
            Flags { geometry: false, light }
        })
        .collect()
}

/// The pixels a triangle thinner than [`THIN_PIXELS`] on screen touches (its footprint, conservatively: the
/// square overlaps it) where their centre shows another surface: a sliver the centres may all miss.
pub fn thin_footprints(scene: &Scene, g: &GBufferData) -> Vec<bool> {
    let (w, h) = (g.size.width, g.size.height);
    let touched: Vec<u32> = (scene.mesh.triangles.par_iter())
        .flat_map_iter(|t| {
            let projected: Option<Vec<Vec2>> = t.v.iter().map(|&v| scene.camera.project(v, w, h)).collect();
            let pixels = projected.and_then(|p| footprint([p[0], p[1], p[2]], (w, h)));
            pixels.into_iter().flatten().filter(move |&i| g.surface[i as usize] != t.surface)
        })
        .collect();
    let mut thin = vec![false; (w * h) as usize];
    for i in touched {
        thin[i as usize] = true;
    }
    thin
}

/// The pixels of a `size` image whose squares overlap the screen triangle `p`, if the triangle is thinner
/// than [`THIN_PIXELS`] (else `None`: the centres find it). Conservative: a square is taken where, for each
/// edge, some corner lies on the triangle's side.
fn footprint(p: [Vec2; 3], (w, h): (u32, u32)) -> Option<Vec<u32>> {
    let cross = |a: Vec2, b: Vec2| a.x * b.y - a.y * b.x;
    let area2 = cross(p[1] - p[0], p[2] - p[0]);
    let longest = (0..3).map(|k| (p[(k + 1) % 3] - p[k]).length()).fold(0.0, f32::max);
    if !area2.is_finite() || longest <= 0.0 || area2.abs() / longest >= THIN_PIXELS {
        return None;
    }
    let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
    if hi.x < 0.0 || hi.y < 0.0 || lo.x >= w as f32 || lo.y >= h as f32 {
        return None;
    }
    let sign = if area2 < 0.0 { -1.0 } else { 1.0 };
    let (x0, y0) = (lo.x.max(0.0) as u32, lo.y.max(0.0) as u32);
    let (x1, y1) = ((hi.x as u32).min(w - 1), (hi.y as u32).min(h - 1));
    let mut pixels = Vec::new();
    for y in y0..=y1 {
        for x in x0..=x1 {
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let overlaps = (0..3).all(|k| {
                let (a, b) = (p[k], p[(k + 1) % 3]);
                let e = b - a;
                sign * cross(e, centre - a) + 0.5 * (e.x.abs() + e.y.abs()) >= 0.0
            });
            if overlaps {
                pixels.push(y * w + x);
            }
        }
    }
    Some(pixels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::ImageSize;

    /// A row of five pixels: R 0, 0, 1, 1 on one surface and a bright pixel of another surface beside the
    /// first dark one. The light ends in the second pixel only: the first's neighbours on its surface are as
    /// dark, and another surface's light says nothing.
    #[test]
    fn the_light_ends_where_a_pixel_is_far_darker_than_a_neighbour_on_its_surface() {
        let g = GBufferData {
            size: ImageSize { width: 5, height: 1 },
            position: vec![Vec4::ONE; 5],
            normal: vec![Vec4::new(0.0, 1.0, 0.0, 1.0); 5],
            albedo: vec![Vec4::ONE; 5],
            emission: vec![Vec4::ZERO; 5],
            surface: vec![2, 1, 1, 1, 1],
        };
        let r: Vec<Vec4> = [5.0, 0.0, 0.1, 1.0, 1.0].iter().map(|&v| Vec4::new(v, v, v, 1.0)).collect();
        let ends = |planned: &[u32]| light_ends(&g, &r, planned).iter().map(|f| f.light).collect::<Vec<_>>();
        assert_eq!(ends(&[]), [false, true, true, false, false], "0 < ¼·0.1 and 0.1 < ¼·1");
        assert_eq!(ends(&[2]), [false, true, false, false, false], "a planned pixel is not flagged again");
        assert!(light_ends(&g, &r, &[]).iter().all(|f| !f.geometry));
    }

    #[test]
    fn a_sliver_between_centres_touches_the_pixels_it_crosses_and_a_large_triangle_is_left_to_the_centres() {
        // A horizontal sliver 0.2 px thick at y ≈ 2.1 (between the centres of rows 1 and 2), x from 1 to 5.
        let sliver = [Vec2::new(1.0, 2.0), Vec2::new(5.0, 2.0), Vec2::new(5.0, 2.2)];
        let pixels = footprint(sliver, (8, 8)).expect("thin");
        assert!(pixels.iter().all(|&i| i / 8 == 2 || i / 8 == 1), "{pixels:?}");
        assert!((1..5).all(|x| pixels.contains(&(2 * 8 + x))), "every pixel of row 2 it crosses: {pixels:?}");
        assert!(!pixels.contains(&(2 * 8 + 6)), "not beyond its end");
        let large = [Vec2::new(0.0, 0.0), Vec2::new(8.0, 0.0), Vec2::new(0.0, 8.0)];
        assert_eq!(footprint(large, (8, 8)), None);
    }
}
