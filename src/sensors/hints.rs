//! Light hints for the refinement (paper §III-G, docs/DESIGN.md §3): which of a few points on each light
//! group every surface pixel can see, by shadow rays on the CPU. Sensors sit at a quad's corners only, so
//! a streak of light narrower than the grid (light through a door ajar) can pass between four dark corners
//! and be interpolated away; a quad is interpolated only where every pixel in it sees the same points. The
//! hints decide only where to sense: every value still comes from a sensor.
//!
//! Cost: pixels × points rays (at most [`MAX_POINTS`] per pixel), about 0.1 s for a 320 × 240 image with one
//! light group on 2 cores.

use glam::Vec3;
use rayon::prelude::*;

use crate::gbuffer::GBufferData;
use crate::light::groups::{LightGroup, Lights};
use crate::scene::bvh::Bvh;
use crate::scene::{Aabb, NO_SURFACE, Ray, SkyMap, stratified_point, triangle_area};

/// Points a group is probed at, at most.
pub const POINTS_PER_GROUP: usize = 16;
/// Points in all, at most: a pixel's hint is a 64-bit mask.
pub const MAX_POINTS: usize = 64;

/// A point on an emitter, and the emitter's front normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPoint {
    pub position: Vec3,
    pub normal: Vec3,
}

/// Up to [`POINTS_PER_GROUP`] points on each group (fewer with more than 4 groups, [`MAX_POINTS`] in all),
/// spread over the group's emitters in proportion to their area: a stratified choice of triangle, then a
/// low-discrepancy point on it. Deterministic.
pub fn light_points(lights: &Lights) -> Vec<LightPoint> {
    (lights.groups.iter().zip(point_groups(lights)))
        .flat_map(|(group, n)| group_points(lights, group, n).into_iter().map(|(point, _)| point))
        .collect()
}

/// `n` points on `group`'s emitters in proportion to their area (a stratified choice of triangle, then a
/// low-discrepancy point on it), each with its emitter's `Ke`; none for a group of no area. Deterministic.
pub fn group_points(lights: &Lights, group: &LightGroup, n: usize) -> Vec<(LightPoint, Vec3)> {
    let emitters = &lights.emitters[group.emitters.start as usize..group.emitters.end as usize];
    let areas: Vec<f32> = emitters.iter().map(|e| triangle_area(&e.v)).collect();
    let total: f32 = areas.iter().sum();
    if total <= 0.0 {
        return Vec::new();
    }
    (0..n)
        .map(|k| {
            let (i, u, v) = stratified_point(&areas, total, k, n);
            let e = &emitters[i];
            let (a, b) = (e.v[1] - e.v[0], e.v[2] - e.v[0]);
            (LightPoint { position: e.v[0] + a * u + b * v, normal: a.cross(b).normalize_or_zero() }, e.ke)
        })
        .collect()
}

fn points_per_group(lights: &Lights) -> usize {
    (MAX_POINTS / lights.groups.len().max(1)).min(POINTS_PER_GROUP)
}

/// Points standing for a sky map in the hints, after the groups' (up to [`MAX_POINTS`] in all, at most
/// [`POINTS_PER_GROUP`]): directions drawn by the map's luminance (`SkyMap::sample` of a stratified set), each
/// as a point 10⁴ diagonals of `bounds` away from its centre (as far as the sun's disc) facing the scene. A
/// bright patch of sky gets most of them, so a quad across its shadow is split as one across an emitter's
/// shadow is. None for a black map.
pub fn sky_points(sky: &SkyMap, bounds: &Aabb, taken: usize) -> Vec<LightPoint> {
    let n = MAX_POINTS.saturating_sub(taken).min(POINTS_PER_GROUP);
    let distance = 1e4 * bounds.diagonal().max(f32::MIN_POSITIVE);
    (0..n)
        .filter_map(|k| {
            // A rank-1 lattice (Fibonacci-like): even over the square for any n.
            let u = glam::Vec2::new((k as f32 + 0.5) / n as f32, (k as f32 * 0.618_034).fract());
            let (d, _) = sky.sample(u)?;
            Some(LightPoint { position: bounds.center() + d * distance, normal: -d })
        })
        .collect()
}

/// How many of [`light_points`] each light group has, in order (0 for a group of no area).
fn point_groups(lights: &Lights) -> Vec<usize> {
    let area = |g: &LightGroup| -> f32 {
        lights.emitters[g.emitters.start as usize..g.emitters.end as usize].iter().map(|e| triangle_area(&e.v)).sum()
    };
    lights.groups.iter().map(|g| if area(g) > 0.0 { points_per_group(lights) } else { 0 }).collect()
}

/// Each light group's bits in a hint mask (its points of [`light_points`]).
pub fn group_bits(lights: &Lights) -> Vec<u64> {
    let mut first = 0;
    point_groups(lights)
        .into_iter()
        .map(|n| {
            let bits = if n == 0 { 0 } else { (u64::MAX >> (64 - n)) << first };
            first += n;
            bits
        })
        .collect()
}

/// Per pixel of `g`, bit k set where the sensor there (at `p + n·bias`, seeing from `near` on) sees point k
/// of `points`: above its horizon, on the emitter's front, nothing between. 0 on the background.
pub fn hints(bvh: &Bvh, points: &[LightPoint], g: &GBufferData, bias: f32, near: f32) -> Vec<u64> {
    (0..g.surface.len())
        .into_par_iter()
        .map(|i| {
            if g.surface[i] == NO_SURFACE {
                return 0;
            }
            mask(bvh, points, (g.position[i].truncate(), g.normal[i].truncate()), bias, near)
        })
        .collect()
}

/// Bit k set where a sensor on the surface at `p` facing `n` (at `p + n·bias`, seeing from `near` on) sees
/// point k of `points`: [`hints`] for one point.
pub fn mask(bvh: &Bvh, points: &[LightPoint], (p, n): (Vec3, Vec3), bias: f32, near: f32) -> u64 {
    masks(bvh, points, (p, n), bias, near).1
}

/// [`mask`], and before it the points a sensor there could see: above its horizon, on the emitter's front,
/// beyond `near` (whether or not something hides them).
pub fn masks(bvh: &Bvh, points: &[LightPoint], (p, n): (Vec3, Vec3), bias: f32, near: f32) -> (u64, u64) {
    masks_among(bvh, points, (p, n), (bias, near), u64::MAX)
}

/// [`masks`] for the points whose bits `among` holds (no ray to the others, whose bits stay clear): a
/// caller that needs some groups' shares only (`hints::group_bits`) casts only their rays.
pub fn masks_among(
    bvh: &Bvh,
    points: &[LightPoint],
    (p, n): (Vec3, Vec3),
    (bias, near): (f32, f32),
    among: u64,
) -> (u64, u64) {
    let origin = p + n * bias;
    let (mut facing, mut mask) = (0u64, 0u64);
    for (k, q) in points.iter().enumerate().take(MAX_POINTS) {
        if among & (1 << k) == 0 {
            continue;
        }
        let d = q.position - origin;
        let length = d.length();
        if d.dot(n) <= 0.0 || q.normal.dot(-d) <= 0.0 || length <= near {
            continue;
        }
        facing |= 1 << k;
        // t in multiples of d: the point itself is at 1; stop just short of its own triangle.
        if !bvh.occluded(&Ray::new(origin, d), near / length, 1.0 - 1e-4) {
            mask |= 1 << k;
        }
    }
    (facing, mask)
}

/// Per light group (`bits`: [`group_bits`]), the share of its points that `visible` holds of those `facing`
/// holds, or of all its points where `facing` is `None`; −1 where none is counted.
pub fn shares(bits: &[u64], facing: Option<u64>, visible: u64) -> [f32; crate::gpu_types::MAX_GROUPS] {
    let mut out = [-1.0; crate::gpu_types::MAX_GROUPS];
    for (share, &b) in out.iter_mut().zip(bits) {
        let counted = b & facing.unwrap_or(u64::MAX);
        if counted != 0 {
            *share = (visible & counted).count_ones() as f32 / counted.count_ones() as f32;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::ImageSize;
    use crate::scene::builtin::lightbox;
    use crate::sensors::frame;

    #[test]
    fn points_lie_on_the_lights_and_the_block_hides_some_of_them() {
        let scene = lightbox(ImageSize { width: 4, height: 4 });
        let lights = Lights::new(&scene.mesh);
        let points = light_points(&lights);
        assert_eq!(points.len(), POINTS_PER_GROUP, "one light group");
        assert!(
            points.iter().all(|p| (p.position.y - 1.99).abs() < 1e-4 && p.normal.y < -0.99),
            "on the light, facing down"
        );
        // Floor pixels: one in the open sees every point, one in the block's penumbra some, one at its foot none.
        let floor = |x: f32, z: f32| (Vec3::new(x, 0.0, z), Vec3::Y);
        let at = [floor(-0.6, 0.5), floor(0.9, -0.2), floor(0.56, -0.2)];
        let g = GBufferData {
            size: ImageSize { width: 3, height: 1 },
            position: at.iter().map(|(p, _)| p.extend(1.0)).collect(),
            normal: at.iter().map(|(_, n)| n.extend(1.0)).collect(),
            albedo: vec![glam::Vec4::ONE; 3],
            emission: vec![glam::Vec4::ZERO; 3],
            surface: vec![1; 3],
        };
        let (bias, near) = frame::offsets(scene.mesh.scale());
        let bvh = Bvh::of_mesh(&scene.mesh);
        let masks = hints(&bvh, &points, &g, bias, near);
        let all = (1u64 << points.len()) - 1;
        assert_eq!(masks[0], all, "in the open, every point is seen");
        assert!(masks[1] != all && masks[1] != 0, "in the penumbra, the block hides part of the light: {:b}", masks[1]);
        assert_eq!(masks[2], 0, "at the block's foot, in its umbra");
    }
}
