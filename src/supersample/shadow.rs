//! A sample's visibility of a light group by shadow rays (step 3 of `supersample`), where the group's light
//! is uneven around the pixel.
//!
//! Between pixel centres a visibility is a ramp with a kink where a penumbra ends: interpolated linearly
//! from the centres, a pixel whose centre sees none of the light but whose square reaches into the penumbra
//! came out twice as bright as its square's mean on the small light's floor (most of that scene's error over
//! the whole image), and the light hints' 16 points are too coarse to place the kink. Each sample of such a
//! pixel instead casts [`SHADOW_RAYS`] rays to points on the group: its light from the group is the rays'
//! share times the group's irradiance there, and the donor's is taken out of the donor's R as it was
//! sensed (what that R holds). Taking the donor's out by the same rays instead (the difference exact where
//! both see the same points) kept the sensor's own error at a penumbra's end in every sample: the Cornell
//! box's interior (direct light, 256²) 2.18 % against 1.97 % now. The points are interleaved over a
//! pixel's samples ([`ShadowPoints::of_sample`]): together a pixel's samples cast [`SHADOW_RAYS`] ×
//! `SAMPLES` rays at as many points of the group, each sample's set chosen by a permutation that changes
//! from pixel to pixel ([`point_set`]).

use glam::Vec3;

use super::SAMPLES;
use crate::gpu_types::MAX_GROUPS;
use crate::light::groups::{Lights, luminance};
use crate::scene::Ray;
use crate::scene::bvh::Bvh;
use crate::sensors::hints;
use crate::sensors::refine::Visibility;

/// Shadow rays per light group a sample casts where the group's light is uneven around its pixel (and its
/// donor as many). 16 × 64 samples = 1 024 points of the group per pixel: the small light's whole image
/// 320 × 240 (direct light) measured 1.42 % with 16, against 2.43 % interpolated.
pub const SHADOW_RAYS: usize = 16;

/// A point on an emitter: where, its front normal, and its radiance's luminance (a point's weight).
#[derive(Clone, Copy, Debug)]
struct Point {
    position: Vec3,
    normal: Vec3,
    luminance: f32,
}

/// Points on each light group, spread over its emitters in proportion to area (`hints::group_points`, as the
/// light hints' points): [`SHADOW_RAYS`] × `SAMPLES` for a pixel's samples ([`ShadowPoints::new`]), or as
/// many as asked for one point's whole share ([`ShadowPoints::share`]: the radiance cache's direct light).
/// Deterministic: a render's bytes do not change.
pub struct ShadowPoints {
    groups: Vec<Vec<Point>>,
}

impl ShadowPoints {
    /// The points a supersampled pixel's samples cast at.
    pub fn new(lights: &Lights) -> Self {
        Self::with_count(lights, SHADOW_RAYS * SAMPLES)
    }

    /// `count` points on each group.
    pub fn with_count(lights: &Lights, count: usize) -> Self {
        let groups = (lights.groups.iter())
            .map(|group| {
                (hints::group_points(lights, group, count).into_iter())
                    .map(|(p, ke)| Point { position: p.position, normal: p.normal, luminance: luminance(ke) })
                    .collect()
            })
            .collect();
        Self { groups }
    }

    /// The points sample `k` of a pixel casts at for `group`: every `SAMPLES`-th from the `k`-th, so that
    /// each sample's points spread over the whole group and the pixel's samples share none.
    fn of_sample(&self, group: usize, k: usize) -> impl Iterator<Item = &Point> {
        self.groups[group].iter().skip(k % SAMPLES).step_by(SAMPLES)
    }

    /// For each group in `groups` (a bit each), the share of its light that a sensor on the surface at `p`
    /// facing `n` (at `p + n·bias`, seeing from `near` on) receives unoccluded, by sample `k`'s points: each
    /// point weighs its radiance times the two cosines over the squared distance (its share of the
    /// irradiance; the points stand for equal areas). −1 for the groups not asked, or where no point is
    /// above the horizon and facing.
    pub fn visibility(
        &self,
        bvh: &Bvh,
        (p, n): (Vec3, Vec3),
        (bias, near): (f32, f32),
        groups: u32,
        k: usize,
    ) -> Visibility {
        let mut out = [-1.0; MAX_GROUPS];
        for (group, v) in out.iter_mut().enumerate().take(self.groups.len()) {
            if groups & (1 << group) != 0 {
                *v = weighted_share(bvh, self.of_sample(group, k), (p, n), (bias, near)).unwrap_or(-1.0);
            }
        }
        out
    }

    /// The share of `group`'s light that a sensor on the surface at `p` facing `n` receives unoccluded, by
    /// every point of the group (weighed as in [`ShadowPoints::visibility`]); `None` where no point is above
    /// the horizon and facing.
    pub fn share(&self, bvh: &Bvh, (p, n): (Vec3, Vec3), offsets: (f32, f32), group: usize) -> Option<f32> {
        weighted_share(bvh, self.groups[group].iter(), (p, n), offsets)
    }

    /// [`ShadowPoints::share`] where the light hints saw none of `group` (a gap narrower than their spacing is
    /// what may still let light through): every [`PROBE`]-th point first, and the others only where one of
    /// those is seen. Most such points see none of it (53 000 of the 0.55M hall's cache entries' 55 000
    /// groups), which the probe's 64 rays then say for a quarter of the 256.
    pub fn share_if_seen(&self, bvh: &Bvh, (p, n): (Vec3, Vec3), offsets: (f32, f32), group: usize) -> Option<f32> {
        let points = &self.groups[group];
        let (seen, total) = weighted(bvh, points.iter().step_by(PROBE), (p, n), offsets);
        if seen == 0.0 && total > 0.0 {
            return Some(0.0);
        }
        let rest = points.iter().enumerate().filter(|(k, _)| k % PROBE != 0).map(|(_, q)| q);
        let (rest_seen, rest_total) = weighted(bvh, rest, (p, n), offsets);
        let total = total + rest_total;
        (total > 0.0).then(|| (seen + rest_seen) / total)
    }
}

/// One point in this many is cast first by [`ShadowPoints::share_if_seen`]: 64 of the cache's 256, four times
/// the hints' density. A gap all 64 miss passes about a 64th of the group's light or less; on hall-40000,
/// the Cornell box, the room, the small light and the door ajar (a room lit through a gap) the images
/// moved 0.01 % or less against their oracles (docs/BENCHMARKS.md).
pub const PROBE: usize = 4;

/// The unoccluded share of `points`' weights (radiance times the two cosines over the squared distance) seen
/// from `p + n·bias`, from `near` on; `None` where none weighs.
fn weighted_share<'a>(
    bvh: &Bvh,
    points: impl Iterator<Item = &'a Point>,
    (p, n): (Vec3, Vec3),
    offsets: (f32, f32),
) -> Option<f32> {
    let (seen, total) = weighted(bvh, points, (p, n), offsets);
    (total > 0.0).then(|| seen / total)
}

/// The seen and the total weight of `points` from `p + n·bias`, from `near` on.
fn weighted<'a>(
    bvh: &Bvh,
    points: impl Iterator<Item = &'a Point>,
    (p, n): (Vec3, Vec3),
    (bias, near): (f32, f32),
) -> (f32, f32) {
    let origin = p + n * bias;
    let (mut seen, mut total) = (0.0, 0.0);
    for q in points {
        let d = q.position - origin;
        let length = d.length();
        let weight = q.luminance * d.dot(n).max(0.0) * q.normal.dot(-d).max(0.0) / length.powi(4);
        if weight <= 0.0 || length <= near {
            continue;
        }
        total += weight;
        // t in multiples of d: the point itself is at 1; stop just short of its own triangle.
        if !bvh.occluded(&Ray::new(origin, d), near / length, 1.0 - 1e-4) {
            seen += weight;
        }
    }
    (seen, total)
}

/// Which of a pixel's [`SAMPLES`] sets of points its sample `k` casts at: a permutation of the sample
/// indices that changes from pixel to pixel (a few invertible steps on 6 bits, salted by the pixel). With
/// set `k` for sample `k`, a sample's place in the square (x = k/64) and its set's offset on the light (an
/// additive recurrence in k) lie on one lattice: at a penumbra's end, where a pixel sees one percent of the
/// light, the pairing made some pixels twice too bright. With the permutation (and the donor's sensed light
/// taken out) the small light's whole image (direct light, 320 × 240) is 0.84 % off instead of 0.96 %.
pub fn point_set(k: usize, pixel: u32) -> usize {
    const { assert!(SAMPLES.is_power_of_two(), "the steps are invertible on log2(SAMPLES) bits") };
    let mask = SAMPLES - 1;
    let h = (pixel as usize).wrapping_mul(0x9E37_79B9) ^ (pixel as usize >> 7).wrapping_mul(0x85EB_CA6B);
    let mut x = (k ^ h) & mask;
    x = (x.wrapping_mul(29).wrapping_add(h >> 6)) & mask;
    x ^= x >> 3;
    x = (x.wrapping_mul(45).wrapping_add(h >> 12)) & mask;
    x ^= x >> 2;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::scene::ImageSize;
    use crate::scene::builtin::lightbox;
    use crate::sensors::frame;

    /// Where the probe sees none of the light (the block's foot) the answer is 0 without the other points;
    /// where it sees some (the penumbra, the open) it is every point's share, as [`ShadowPoints::share`].
    #[test]
    fn the_probe_answers_as_every_point_does() {
        let scene = lightbox(ImageSize { width: 4, height: 4 });
        let lights = Lights::new(&scene.mesh);
        let bvh = Bvh::of_mesh(&scene.mesh);
        let offsets = frame::offsets(scene.mesh.scale());
        let points = ShadowPoints::with_count(&lights, 256);
        for (x, z) in [(0.56, -0.2), (0.9, -0.2), (-0.6, 0.5), (0.7, -0.2)] {
            let at = (Vec3::new(x, 0.0, z), Vec3::Y);
            let (all, probed) = (points.share(&bvh, at, offsets, 0), points.share_if_seen(&bvh, at, offsets, 0));
            let (all, probed) = (all.unwrap(), probed.unwrap());
            assert!((all - probed).abs() < 1e-5, "at ({x}, {z}): every point {all}, probed {probed}");
        }
        let foot = (Vec3::new(0.56, 0.0, -0.2), Vec3::Y);
        assert_eq!(points.share_if_seen(&bvh, foot, offsets, 0), Some(0.0), "at the block's foot");
        let penumbra = points.share(&bvh, (Vec3::new(0.9, 0.0, -0.2), Vec3::Y), offsets, 0).unwrap();
        assert!(penumbra > 0.05 && penumbra < 0.95, "in the penumbra: {penumbra}");
    }

    #[test]
    fn each_pixel_gives_its_samples_every_set_once_in_its_own_order() {
        let order = |pixel: u32| (0..SAMPLES).map(|k| point_set(k, pixel)).collect::<Vec<_>>();
        for pixel in [0, 1, 2, 319, 76_799, u32::MAX] {
            let mut sets = order(pixel);
            sets.sort();
            assert_eq!(sets, (0..SAMPLES).collect::<Vec<_>>(), "pixel {pixel}: a permutation");
        }
        assert!((1..100).all(|pixel| order(pixel) != order(0)), "the order changes from pixel to pixel");
    }

    /// On the light box's floor: in the open every ray sees the light, at the block's foot none, and in its
    /// penumbra a pixel's 1 024 points agree with a dense independent quadrature of the light (a 256 × 256
    /// grid on each emitter triangle, weighted alike) within 2 %.
    #[test]
    fn the_share_of_the_light_a_point_sees() {
        let scene = lightbox(ImageSize { width: 4, height: 4 });
        let lights = Lights::new(&scene.mesh);
        let bvh = Bvh::of_mesh(&scene.mesh);
        let scale = scene.mesh.scale();
        let offsets = frame::offsets(scale);
        let points = ShadowPoints::new(&lights);
        let at = |x: f32, z: f32, k: usize| points.visibility(&bvh, (Vec3::new(x, 0.0, z), Vec3::Y), offsets, 1, k)[0];
        assert_eq!(at(-0.6, 0.5, 0), 1.0, "in the open");
        assert_eq!(at(0.56, -0.2, 0), 0.0, "at the block's foot");
        assert_eq!(points.visibility(&bvh, (Vec3::new(-0.6, 0.0, 0.5), Vec3::Y), offsets, 0, 0)[0], -1.0, "not asked");
        // Over all of a pixel's samples (1 024 points), the penumbra's share.
        let mean = (0..SAMPLES).map(|k| at(0.9, -0.2, k)).sum::<f32>() / SAMPLES as f32;
        let (origin, n) = (Vec3::new(0.9, 0.0, -0.2) + Vec3::Y * offsets.0, Vec3::Y);
        let (mut seen, mut total) = (0.0f64, 0.0f64);
        let m = 256;
        for e in &lights.emitters {
            let normal = (e.v[1] - e.v[0]).cross(e.v[2] - e.v[0]).normalize();
            for (i, j) in (0..m).flat_map(|i| (0..m - i).map(move |j| (i, j))) {
                let (u, v) = ((i as f32 + 1.0 / 3.0) / m as f32, (j as f32 + 1.0 / 3.0) / m as f32);
                let d = e.v[0] + (e.v[1] - e.v[0]) * u + (e.v[2] - e.v[0]) * v - origin;
                let weight = (d.dot(n).max(0.0) * normal.dot(-d).max(0.0) / d.length().powi(4)) as f64;
                total += weight;
                if !bvh.occluded(&Ray::new(origin, d), offsets.1 / d.length(), 1.0 - 1e-4) {
                    seen += weight;
                }
            }
        }
        let dense = (seen / total) as f32;
        assert!(dense > 0.05 && dense < 0.95, "in the penumbra: {dense}");
        assert!((mean - dense).abs() < 0.02, "a pixel's points {mean} against the dense quadrature {dense}");
    }
}
