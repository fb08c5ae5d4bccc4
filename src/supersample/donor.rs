//! Where each sub-pixel sample's R comes from (step 3 of `supersample`): its donor, the nearest pixel on its
//! surface, or the radiance cache where no pixel around shows its surface; and with the exact light each
//! group's visibility at the sample and at the donor.

use std::collections::BTreeMap;
use std::ops::Range;

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::detect::Point;
use super::shadow::{ShadowPoints, point_set};
use super::{Plan, SAMPLES, Samples, neighbourhood};
use crate::gbuffer::GBufferData;
use crate::gpu_types::{GpuSubSample, MAX_GROUPS};
use crate::light::groups::Lights;
use crate::scene::bvh::Bvh;
use crate::scene::{NO_SURFACE, SurfaceId};
use crate::sensors::hints::{self, LightPoint};
use crate::sensors::refine::Visibility;

/// What the samples' light groups are judged with (exact estimator and interpolation only).
pub struct SubSampleLight<'a> {
    /// Every pixel's visibilities as the render has them (`refine::visibility_everywhere`).
    pub visibility: &'a [Visibility],
    /// Every pixel's light hint (`sensors::hints`).
    pub hints: &'a [u64],
    pub bvh: &'a Bvh,
    /// The light hints' points and each group's bits among them (`hints::group_bits`).
    pub points: &'a [LightPoint],
    pub bits: &'a [u64],
    /// Points on each group that a sample casts shadow rays at where the group's light is uneven.
    pub shadow: &'a ShadowPoints,
    /// A sensor's lift and near distance (`sensors::frame`).
    pub bias: f32,
    pub near: f32,
}

/// The radiance cache as the camera's sensors read it (global illumination only). A sample on a surface no
/// pixel of its 3 × 3 shows (another room seen through a door's gap, a sliver) takes its R from there: a
/// pixel of another surface lent it its own indirect light, and the door ajar's gap, a sixth of a pixel
/// wide onto the lit room's jamb and far wall, was a tenth as bright as the path tracer's.
pub struct SubSampleCache<'a> {
    /// The value a point on a surface's side (`front`) reads, seen from the camera (the renderer's cache).
    pub read: &'a (dyn Fn(Vec3, SurfaceId, bool) -> CacheValue + Sync),
    /// The lights: with the exact light, their light where the value was sensed is taken out of its R, and
    /// the resolve adds it at the sample.
    pub lights: &'a Lights,
}

/// A radiance cache value as a sample reads it.
pub struct CacheValue {
    /// Which value (the same for the samples that read it).
    pub index: usize,
    /// R there: the value (`Kd·R`) over its `Kd`.
    pub r: Vec3,
    /// Where its sensor was, and its normal (`None`: a surface side's fallback, sensed nowhere).
    pub sensed_at: Option<(Vec3, Vec3)>,
}

/// The resolve's input for the supersampled pixels `range` of `plan`, one per sample of `samples`
/// (`Plan::samples`: what they see, where, and their weights), against the centres' G-buffer `g`:
///
/// - the donor: among the pixel and its 8 neighbours, the nearest (centre to the sample's point) whose
///   centre shows the sample's surface alike (`detect::Point::alike`), else the nearest of the sample's
///   id, else the nearest showing any surface, else the pixel itself;
/// - with `light`, each group's visibility at the sample: where the donor shows its surface, bilinear
///   between the four pixel centres around the sample that do ([`bilinear`]; the donor's where none does),
///   with the light hints' detail inside the pixel ([`with_hint_detail`]); else (a sliver no centre shows)
///   the share of the group's hint points in front of the sample that it sees, or the donor's where none
///   is in front; but for the groups whose light is uneven around the sample (every group where the plan
///   flags the pixel's light or no centre shows the sample's surface, else [`uneven`]), the share of
///   the group's light the sample sees by shadow rays (`shadow`), and the donor's as it was sensed (what
///   its R holds), or by the same rays where it was not measured;
/// - with `cache`, a sample on a surface no pixel of the 3 × 3 shows takes as its own R the cache's at its
///   point, less the lights' light at the entry's point where the resolve adds it at the sample
///   ([`SubSampleCache`]).
pub fn sub_samples(
    g: &GBufferData,
    (plan, range, taken): (&Plan, Range<usize>, &Samples),
    light: Option<SubSampleLight<'_>>,
    cache: Option<SubSampleCache<'_>>,
) -> Vec<GpuSubSample> {
    let samples = &taken.seen;
    type Read = Option<(usize, Option<(Vec3, Vec3)>)>;
    let (mut records, reads): (Vec<GpuSubSample>, Vec<Read>) = (0..samples.surface.len())
        .into_par_iter()
        .map(|s| {
            let (n, k) = (range.start + s / SAMPLES, s % SAMPLES);
            let (sample, at) = (Point::of(samples, s), taken.points[s]);
            let (donor, same_surface) = donor(g, plan.pixels[n], at, &sample);
            let mut record = GpuSubSample {
                position: samples.position[s].to_array(),
                normal: samples.normal[s].to_array(),
                albedo: samples.albedo[s].to_array(),
                donor,
                weight: taken.weights[s],
                ..Default::default()
            };
            if let Some(l) = light.as_ref().filter(|_| sample.surface != NO_SURFACE) {
                let donor_visibility = l.visibility[donor as usize];
                record.donor_visibility = donor_visibility;
                // First the groups whose light is uneven around the sample: their visibility comes from
                // shadow rays, and the hints' rays need not be cast at their points.
                let all = (1 << l.bits.len().min(MAX_GROUPS)) - 1;
                let groups = if plan.light[n] { all } else { uneven(g, l, plan.pixels[n], &sample).unwrap_or(all) };
                let mut traced = [-1.0; MAX_GROUPS];
                let mut traced_donor = [-1.0; MAX_GROUPS];
                if groups != 0 {
                    let offsets = (l.bias, l.near);
                    let set = point_set(k, plan.pixels[n]);
                    let at_sample = (samples.position[s].truncate(), samples.normal[s].truncate());
                    traced = l.shadow.visibility(l.bvh, at_sample, offsets, groups, set);
                    // The donor's light is taken out as it was sensed (what its R holds); by the same rays
                    // only where it was not measured.
                    let unmeasured = (0..MAX_GROUPS)
                        .filter(|&group| groups & (1 << group) != 0 && donor_visibility[group] < 0.0)
                        .fold(0, |mask, group| mask | 1 << group);
                    if unmeasured != 0 {
                        let at_donor = (g.position[donor as usize].truncate(), g.normal[donor as usize].truncate());
                        traced_donor = l.shadow.visibility(l.bvh, at_donor, offsets, unmeasured, set);
                    }
                }
                let by_rays = |group: usize| {
                    traced[group] >= 0.0 && (donor_visibility[group] >= 0.0 || traced_donor[group] >= 0.0)
                };
                // The hint points of the groups the shadow rays leave as they are.
                let among =
                    (l.bits.iter().enumerate()).filter(|&(group, _)| !by_rays(group)).fold(0, |m, (_, b)| m | b);
                let masks = |(p, normal): (Vec3, Vec3)| {
                    hints::masks_among(l.bvh, l.points, (p, normal), (l.bias, l.near), among)
                };
                record.visibility = match same_surface {
                    true => match bilinear(g, &|i| l.visibility[i], at, &sample) {
                        Some(v) => with_hint_detail(
                            v,
                            (l, &masks),
                            (g, at, &sample),
                            (plan.pixels[n], &samples.position[s], &samples.normal[s]),
                        ),
                        None => donor_visibility,
                    },
                    // A sliver no centre shows: the share of each group's hint points it sees.
                    false => {
                        let (facing, visible) = masks((samples.position[s].truncate(), samples.normal[s].truncate()));
                        let share = hints::shares(l.bits, Some(facing), visible);
                        std::array::from_fn(|g| if share[g] < 0.0 { donor_visibility[g] } else { share[g] })
                    }
                };
                for group in (0..MAX_GROUPS).filter(|&group| by_rays(group)) {
                    record.visibility[group] = traced[group];
                    if donor_visibility[group] < 0.0 {
                        record.donor_visibility[group] = traced_donor[group];
                    }
                }
            }
            // A surface no pixel around shows: the cache's R at the sample.
            let read = cache.as_ref().filter(|_| !same_surface && sample.surface != NO_SURFACE).map(|c| {
                let front = samples.normal[s].w == 1.0;
                let value = (c.read)(samples.position[s].truncate(), sample.surface, front);
                record.own = value.r.extend(1.0).to_array();
                (value.index, value.sensed_at)
            });
            (record, read)
        })
        .unzip();
    // With the exact light, the resolve adds the lights' light at the sample: take it out of the cache's R
    // as it is at the entry's point (shadow rays to every point of each group), once per entry read.
    if let (Some(c), Some(l)) = (&cache, &light) {
        let sensed: BTreeMap<usize, (Vec3, Vec3)> =
            reads.iter().flatten().filter_map(|&(index, at)| Some((index, at?))).collect();
        let direct: BTreeMap<usize, Vec3> = sensed
            .into_par_iter()
            .map(|(index, (p, n))| {
                let unoccluded = c.lights.unoccluded(p + n * l.bias, n);
                let seen = (0..c.lights.groups.len().min(MAX_GROUPS))
                    .map(|group| {
                        unoccluded[group] * l.shadow.share(l.bvh, (p, n), (l.bias, l.near), group).unwrap_or(0.0)
                    })
                    .sum::<Vec3>();
                (index, seen / std::f32::consts::PI)
            })
            .collect();
        for (record, read) in records.iter_mut().zip(&reads) {
            if let Some(d) = read.and_then(|(index, _)| direct.get(&index)) {
                let own = Vec4::from(record.own);
                record.own = (own.truncate() - *d).max(Vec3::ZERO).extend(1.0).to_array();
            }
        }
    }
    records
}

/// The light groups (a bit each) whose light is uneven around a sample of supersampled pixel `pixel` of `g`
/// that shows `sample`: the visibilities or the light hints' shares differ between the pixels of the 3 × 3
/// neighbourhood that show its surface alike (those its light is interpolated from); `None` where none does.
fn uneven(g: &GBufferData, l: &SubSampleLight<'_>, pixel: u32, sample: &Point) -> Option<u32> {
    let around: Vec<usize> = neighbourhood(g.size, pixel).filter(|&i| Point::of(g, i).alike(sample)).collect();
    if around.is_empty() {
        return None;
    }
    let differs = |value: &dyn Fn(usize) -> Visibility, group: usize| {
        let values = around.iter().map(|&i| value(i)[group]).filter(|v| *v >= 0.0);
        let (lo, hi) = values.fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
        hi - lo > 1e-3
    };
    let share =
        |i: usize| if l.hints.is_empty() { [-1.0; MAX_GROUPS] } else { hints::shares(l.bits, None, l.hints[i]) };
    let groups = (0..l.bits.len().min(MAX_GROUPS))
        .filter(|&group| differs(&|i| l.visibility[i], group) || differs(&share, group));
    Some(groups.fold(0, |mask, group| mask | 1 << group))
}

/// A point's light hint masks (`hints::masks`), cast only for the groups whose result counts.
type HintMasks<'a> = &'a dyn Fn((Vec3, Vec3)) -> (u64, u64);

/// `v`, a sample's bilinear visibilities, with the detail the light hints see inside the pixel: the share of
/// each group's hint points the sample sees, less that share bilinear between the same centres (clamped to
/// [0, 1]). A shadow's edge narrower than a pixel is then where the hints put it, not smeared over two
/// pixels as the bilinear visibility alone would; in even light the two shares cancel. Only where the hints
/// of the pixel's 3 × 3 neighbourhood differ (elsewhere there is no detail to add). `masks`: the sample's
/// hint masks for the groups whose result counts.
fn with_hint_detail(
    v: Visibility,
    (l, masks): (&SubSampleLight<'_>, HintMasks<'_>),
    (g, at, sample): (&GBufferData, Vec2, &Point),
    (pixel, position, normal): (u32, &glam::Vec4, &glam::Vec4),
) -> Visibility {
    if l.hints.is_empty() {
        return v;
    }
    let mut hints = neighbourhood(g.size, pixel).map(|i| l.hints[i]);
    let first = hints.next();
    if hints.all(|m| Some(m) == first) {
        return v;
    }
    let share = |mask: u64| hints::shares(l.bits, None, mask);
    let Some(between) = bilinear(g, &|i| share(l.hints[i]), at, sample) else { return v };
    let own = share(masks((position.truncate(), normal.truncate())).1);
    std::array::from_fn(|k| {
        if v[k] < 0.0 || own[k] < 0.0 || between[k] < 0.0 { v[k] } else { (v[k] + own[k] - between[k]).clamp(0.0, 1.0) }
    })
}

/// Per-pixel values `value` (a visibility per group) at the image point `at`, showing `sample`: bilinear
/// between the four pixel centres around it. A centre that does not show the sample's surface alike is
/// extrapolated from the two beyond it along a row or column that do (`2·V_a − V_b`, clamped to [0, 1]), or
/// left out; `None` where no centre is left. A shadow's edge crossing the pixel then moves through its
/// samples as the interpolation moves it between sensed pixels, and a penumbra that runs into a silhouette
/// keeps its slope up to it.
fn bilinear(g: &GBufferData, value: &dyn Fn(usize) -> Visibility, at: Vec2, sample: &Point) -> Option<Visibility> {
    let (w, h) = (g.size.width as i64, g.size.height as i64);
    let base = at - Vec2::splat(0.5);
    let (x0, y0) = (base.x.floor() as i64, base.y.floor() as i64);
    let (fx, fy) = (base.x - x0 as f32, base.y - y0 as f32);
    let alike = |x: i64, y: i64| -> Option<Visibility> {
        let inside = x >= 0 && y >= 0 && x < w && y < h;
        let i = (y * w + x) as usize;
        (inside && Point::of(g, i).alike(sample)).then(|| value(i))
    };
    let corner = |dx: i64, dy: i64| -> Option<Visibility> {
        let (x, y) = (x0 + dx, y0 + dy);
        if let Some(v) = alike(x, y) {
            return Some(v);
        }
        // Along the column, then the row: the neighbour inside the four and the one beyond it.
        let (sy, sx) = (1 - 2 * dy, 1 - 2 * dx);
        let pairs = [((x, y + sy), (x, y + 2 * sy)), ((x + sx, y), (x + 2 * sx, y))];
        pairs.iter().find_map(|&((ax, ay), (bx, by))| {
            let (a, b) = (alike(ax, ay)?, alike(bx, by)?);
            Some(std::array::from_fn(
                |k| if a[k] < 0.0 || b[k] < 0.0 { a[k] } else { (2.0 * a[k] - b[k]).clamp(0.0, 1.0) },
            ))
        })
    };
    let mut sum = [0.0f32; MAX_GROUPS];
    let mut total = 0.0;
    for (dx, dy, weight) in
        [(0, 0, (1.0 - fx) * (1.0 - fy)), (1, 0, fx * (1.0 - fy)), (0, 1, (1.0 - fx) * fy), (1, 1, fx * fy)]
    {
        let Some(v) = corner(dx, dy).filter(|_| weight > 0.0) else { continue };
        for (s, v) in sum.iter_mut().zip(&v) {
            *s += weight * v;
        }
        total += weight;
    }
    (total > 0.0).then(|| sum.map(|s| s / total))
}

/// The donor of a sample at the image point `at` in `pixel`, showing `sample`; and whether it shows the
/// sample's surface (see [`sub_samples`]).
fn donor(g: &GBufferData, pixel: u32, at: Vec2, sample: &Point) -> (u32, bool) {
    let w = g.size.width as usize;
    let around = neighbourhood(g.size, pixel).map(|q| {
        let distance = (Vec2::new((q % w) as f32 + 0.5, (q / w) as f32 + 0.5) - at).length_squared();
        (q as u32, distance)
    });
    let nearest = |accept: &dyn Fn(&Point) -> bool| {
        around
            .clone()
            .filter(|&(q, _)| accept(&Point::of(g, q as usize)))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
            .map(|(q, _)| q)
    };
    if let Some(q) = nearest(&|p| p.alike(sample)) {
        return (q, true);
    }
    if let Some(q) = nearest(&|p| p.surface == sample.surface) {
        return (q, true);
    }
    (nearest(&|p| p.surface != NO_SURFACE).unwrap_or(pixel), false)
}

#[cfg(test)]
mod tests {
    use glam::{Vec3, Vec4};

    use super::*;
    use crate::scene::ImageSize;

    /// A 2 × 2 floor (one surface, but pixel 3 is another); group 0 seen 0, 1, 0.5 at pixels 0, 1, 2.
    #[test]
    fn visibility_is_bilinear_over_the_centres_on_the_samples_surface() {
        let position: Vec<Vec4> = (0..4).map(|i| Vec3::new((i % 2) as f32, 0.0, (i / 2) as f32).extend(1.0)).collect();
        let g = GBufferData {
            size: ImageSize { width: 2, height: 2 },
            normal: vec![Vec4::new(0.0, 1.0, 0.0, 1.0); 4],
            albedo: vec![Vec4::ONE; 4],
            emission: vec![Vec4::ZERO; 4],
            surface: vec![1, 1, 1, 2],
            position,
        };
        let visibility: Vec<Visibility> =
            [0.0, 1.0, 0.5, 0.9].iter().map(|&v| std::array::from_fn(|k| if k == 0 { v } else { -1.0 })).collect();
        let sample = Point::of(&g, 0);
        let v = |x: f32, y: f32| bilinear(&g, &|i| visibility[i], Vec2::new(x, y), &sample).unwrap()[0];
        assert_eq!(v(0.5, 0.5), 0.0, "at pixel 0's centre");
        assert!((v(1.0, 0.5) - 0.5).abs() < 1e-6, "halfway between pixels 0 and 1");
        // At the middle of the four centres: pixel 3 shows another surface and nothing lies beyond it to
        // extrapolate from (a 2 × 2 image), so the others weigh ⅓ each.
        assert!((v(1.0, 1.0) - 0.5).abs() < 1e-6, "(0 + 1 + 0.5) / 3, not with pixel 3's 0.9");
    }
}
