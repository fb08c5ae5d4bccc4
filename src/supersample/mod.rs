//! Every pixel right: sub-pixel samples where a pixel is not uniform (docs/DESIGN.md §11).
//!
//! A camera's pixel, and every reference renderer's, is the mean over its square (a box filter); the
//! sensors measure R at the pixel's centre. Inside a surface the two agree; where the square holds an edge
//! (a silhouette, a crease, the rim of a light, a shadow's hard edge) or a sliver thinner than a pixel (a
//! bar, a light seen edge-on), the centre alone is a jagged edge, and most of a render's error against a
//! reference (11.7 % over the whole Cornell box against the path tracer's pixel squares, 0.5 % inside).
//!
//! ```text
//!  1. detect    pixels whose 3×3 neighbourhood differs (id, normal, depth, emission; the light hints'
//!               share of a group jumps) or that a triangle thinner than a pixel touches     (detect.rs)
//!  2. cast      SAMPLES camera rays per such pixel at fixed points of its square, on the CPU's BVH; a
//!               pixel whose samples all agree with its centre, and whose light is even, is dropped;
//!               where two surfaces meet, a denser net of rays weighs each sample by the share of the
//!               square its surface covers                                                 (coverage.rs)
//!  3. donors    after sensing: each sample takes the final R of the nearest pixel on its surface, with
//!               the light groups' exact light recomputed at the sample (donor.rs); where a group's light
//!               is uneven around the pixel, its visibility there by shadow rays            (shadow.rs)
//!  4. resolve   on the GPU after composition: the pixel is Le + Kd·R over its samples by weight, the
//!               sky along its ray where a sample leaves the scene         (glsl/resolve.comp, resolve_cpu)
//!  5. ends      then the pixels far darker than a neighbour on their surface, as sensed and resolved
//!               (the light ends inside them: `light_ends`), planned and resolved the same way
//! ```
//!
//! Why borrowed and not sensed: along an edge the refinement has already sensed the pixels on both sides
//! (a quad with two ids is split to the pixel), so each sample's surface has a sensed or interpolated
//! pixel within one pixel. R varies smoothly within a surface except across shadows, and the exact
//! estimator knows R's fast part in closed form: `R(s) = R(d) + Σ_g (E_g(s)·V_g(s) − E_g(d)·V_g(d))/π` at
//! donor `d`, `E_g` a group's unoccluded irradiance (`Lights::unoccluded`), `V_g(s)` the donor's
//! visibility shifted by the change of the share of the group's hint points (`sensors::hints`) the two
//! points see, which moves a hard shadow's edge into the pixel; where the group's light is uneven around
//! the pixel, `V_g` at the sample and at the donor by the same shadow rays (a penumbra's end is a kink that
//! interpolation between centres makes twice too bright). Sensing each sample instead would cost
//! SAMPLES sensors per edge pixel; measured in docs/ACCURACY.md "Every pixel right".

mod coverage;
mod detect;
mod donor;
mod emission;
mod shadow;

use std::ops::Range;

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

pub use detect::{Flags, detect, light_between_centres, light_ends};
pub use donor::{CacheValue, SubSampleCache, SubSampleLight, sub_samples};
pub use shadow::{SHADOW_RAYS, ShadowPoints};

use crate::gbuffer::GBufferData;
use crate::gbuffer::cast::cast_points;
use crate::gpu_types::{GpuSubSample, GpuSupersampledPixel, MAX_GROUPS};
use crate::light::groups::Lights;
use crate::scene::bvh::Bvh;
use crate::scene::{ImageSize, NO_SURFACE, Scene};

/// Sub-samples per supersampled pixel. A pixel on an edge between a lit and a dark surface, or in a corner,
/// is off by its coverage's error times the contrast, and relative to its own small value: measured on the
/// Cornell box at 128² (ε 0.1) against the pixel-area oracle, the whole image is 1.78 % off with 32, 1.27 %
/// with 64; the rays are cast on the host (0.2 s for 1 600 pixels on 2 cores) and the resolve is a few
/// milliseconds.
pub const SAMPLES: usize = 64;

/// Where a supersampled pixel's samples lie in its square, in [0, 1)²: a Hammersley set (x stratified
/// in eighths, y by the base-2 radical inverse), fixed so that a render is deterministic.
pub fn pattern() -> [Vec2; SAMPLES] {
    std::array::from_fn(|i| {
        let y = (i as u32).reverse_bits() as f32 / 2f32.powi(32);
        Vec2::new((i as f32 + 0.5) / SAMPLES as f32, y + 0.5 / SAMPLES as f32)
    })
}

/// Supersampled pixels handled at once after the plan: their samples are cast, uploaded and resolved a
/// slice at a time (a slice's samples: about 30 MB on the host, 60 MB on the GPU), so that memory stays
/// bounded whatever the image's size.
pub const SLICE: usize = 8_192;

/// The pixels a render supersamples.
#[derive(Clone, Debug, Default)]
pub struct Plan {
    /// Supersampled pixels, each once: in increasing index from [`plan`] (a second plan appended after).
    pub pixels: Vec<u32>,
    /// The mean radiance each pixel's square emits, exactly (`emission::emitted`).
    pub emission: Vec<Vec3>,
    /// Whether each pixel's light is uneven ([`Flags::light`]): its samples cast shadow rays at every
    /// light group (`shadow`), not only at those whose visibility differs around it.
    pub light: Vec<bool>,
}

impl Plan {
    /// `other`'s pixels (none of them in `self`) after `self`'s.
    pub fn append(&mut self, other: Plan) {
        self.pixels.extend(other.pixels);
        self.emission.extend(other.emission);
        self.light.extend(other.light);
    }

    /// The supersampled pixels `range` as the resolve reads them.
    pub fn gpu_pixels(&self, range: Range<usize>) -> Vec<GpuSupersampledPixel> {
        (self.pixels[range.clone()].iter().zip(&self.emission[range]))
            .map(|(&pixel, e)| GpuSupersampledPixel { emission: e.extend(0.0).to_array(), pixel, _pad: [0; 3] })
            .collect()
    }

    /// The samples of the supersampled pixels `range`, [`SAMPLES`] a pixel in order (cast again rather than
    /// kept from the plan: [`SLICE`]), weighed by what their surfaces cover (`coverage`).
    /// `g`: the centres' G-buffer.
    pub fn samples(&self, scene: &Scene, bvh: &Bvh, g: &GBufferData, range: Range<usize>) -> Samples {
        let pixels = &self.pixels[range];
        let points = points_of(pixels, g.size.width);
        let seen = cast_points(scene, bvh, g.size, &points);
        coverage::weigh((scene, bvh, g), pixels, seen, points)
    }
}

/// What some supersampled pixels' samples see ([`SAMPLES`] a pixel), where in the image they lie, and the
/// share of its pixel's square each stands for (they sum to 1 over a pixel's samples).
pub struct Samples {
    pub seen: GBufferData,
    pub points: Vec<Vec2>,
    pub weights: Vec<f32>,
}

/// The image points of the samples of `pixels` (of an image `width` wide), [`SAMPLES`] each.
fn points_of(pixels: &[u32], width: u32) -> Vec<Vec2> {
    (pixels.iter()).flat_map(|&i| pattern().map(|u| Vec2::new((i % width) as f32, (i / width) as f32) + u)).collect()
}

/// Plans the supersampling of the image whose centres `g` holds: of the pixels [`detect`] flags, [`SLICE`]
/// at a time, [`SAMPLES`] camera rays each are cast on `bvh`, and each square's emitted light is computed
/// exactly (`emission::emitted`); a pixel is kept where its light jumps, a sample does not show its
/// centre's surface alike ([`detect::same_surface`]), or it emits other than its centre (an emitter's rim,
/// which the samples may all miss).
pub fn plan(scene: &Scene, bvh: &Bvh, g: &GBufferData, flags: &[Flags]) -> Plan {
    let width = g.size.width;
    let candidates: Vec<u32> = (0..flags.len() as u32).filter(|&i| flags[i as usize].any()).collect();
    let (emitters, sampled) = emission::screen_emitters(scene, g.size);
    let mut plan = Plan::default();
    for slice in candidates.chunks(SLICE) {
        let points = points_of(slice, width);
        let cast = cast_points(scene, bvh, g.size, &points);
        let emitted: Vec<Vec3> = (slice.par_iter().enumerate())
            .map(|(n, &i)| {
                let range = n * SAMPLES..(n + 1) * SAMPLES;
                let seen = (&cast.surface[range.clone()], &cast.emission[range.clone()], &points[range]);
                emission::emitted((scene, bvh, g.size), (&emitters, &sampled), (i % width, i / width), seen)
            })
            .collect();
        for (n, &i) in slice.iter().enumerate() {
            let centre = g.emission[i as usize].truncate();
            let rim =
                (emitted[n] - centre).abs().max_element() > 1e-4 * centre.max_element().max(emitted[n].max_element());
            if flags[i as usize].light
                || rim
                || (n * SAMPLES..(n + 1) * SAMPLES).any(|s| !detect::same_surface(g, i as usize, &cast, s))
            {
                plan.pixels.push(i);
                plan.emission.push(emitted[n]);
                plan.light.push(flags[i as usize].light);
            }
        }
    }
    plan
}

/// Gives each sample of `samples` (at the image `points`) that leaves the scene the sky it sees,
/// `sky(its image point)`, in its albedo, where the resolve reads it.
pub fn carry_sky(samples: &mut [GpuSubSample], points: &[Vec2], sky: impl Fn(Vec2) -> Vec3 + Sync) {
    samples.par_iter_mut().enumerate().filter(|(_, s)| s.position[3] == 0.0).for_each(|(s, record)| {
        record.albedo = sky(points[s]).extend(0.0).to_array();
    });
}

/// The resolve's CPU twin (`glsl/resolve.comp`): per supersampled pixel (`pixels`, each with [`SAMPLES`] of
/// `samples`), the image: its exact emission plus `Kd·R` over its samples, each by its weight (the sky it
/// carries in its albedo where one leaves the scene); and R over those that met a surface, by their weights
/// (the radiance AOV); each with alpha the weight of those that did (coverage).
/// `composed`: every pixel's final R; `g`: the centres' G-buffer (the donors' positions); with `exact`,
/// each light group's light is computed at the sample and at its donor (`lights`, sensors lifted by
/// `bias`).
pub fn resolve_cpu(
    (pixels, samples): (&[GpuSupersampledPixel], &[GpuSubSample]),
    composed: &[Vec4],
    g: &GBufferData,
    (lights, bias, exact): (&Lights, f32, bool),
) -> Vec<(Vec4, Vec4)> {
    let direct = |p: Vec4, n: Vec4, v: &[f32; MAX_GROUPS]| -> Vec3 {
        if p.w == 0.0 {
            return Vec3::ZERO;
        }
        let e = lights.unoccluded(p.truncate() + n.truncate() * bias, n.truncate());
        (0..lights.groups.len()).map(|k| e[k] * if v[k] < 0.0 { 1.0 } else { v[k] }).sum::<Vec3>()
            / std::f32::consts::PI
    };
    (samples.chunks(SAMPLES).zip(pixels))
        .map(|(pixel, p)| {
            let (mut image, mut r, mut hits, mut misses) = (Vec3::ZERO, Vec3::ZERO, 0.0, 0.0);
            for s in pixel {
                let position = Vec4::from(s.position);
                if position.w == 0.0 {
                    image += s.weight * Vec4::from(s.albedo).truncate();
                    misses += s.weight;
                    continue;
                }
                let d = s.donor as usize;
                let own = Vec4::from(s.own);
                let mut rs = if own.w == 1.0 { own.truncate() } else { composed[d].truncate() };
                if exact && own.w == 1.0 {
                    rs += direct(position, Vec4::from(s.normal), &s.visibility);
                } else if exact {
                    let at_donor = direct(g.position[d], g.normal[d], &s.donor_visibility);
                    rs = (rs + direct(position, Vec4::from(s.normal), &s.visibility) - at_donor).max(Vec3::ZERO);
                }
                image += s.weight * Vec4::from(s.albedo).truncate() * rs;
                r += s.weight * rs;
                hits += s.weight;
            }
            let emitted = Vec4::from(p.emission).truncate();
            let mean_r = if hits > 0.0 { r / hits } else { Vec3::ZERO };
            // Exactly 1 where no sample leaves the scene (the weights' sum is 1 ± rounding).
            let coverage = hits / f32::max(hits + misses, 1e-30);
            ((emitted + image).extend(coverage), mean_r.extend(coverage))
        })
        .collect()
}

/// The id that covers most of a supersampled pixel's square, its samples' `ids` each weighing `weights`
/// (the lowest on a tie; the background only where most of it leaves the scene): the `surface_id` AOV of a
/// supersampled pixel.
pub fn majority_id(ids: &[u32], weights: &[f32]) -> u32 {
    let mut best = (0.0, NO_SURFACE);
    for &id in ids {
        let share: f32 = ids.iter().zip(weights).filter(|(other, _)| **other == id).map(|(_, w)| w).sum();
        if share > best.0 || (share == best.0 && id < best.1) {
            best = (share, id);
        }
    }
    best.1
}

/// The pixels of `pixel`'s 3 × 3 neighbourhood in an image of `size` (itself included), row by row.
pub(super) fn neighbourhood(size: ImageSize, pixel: u32) -> impl Iterator<Item = usize> + Clone {
    let (w, h) = (size.width as i64, size.height as i64);
    let (x, y) = ((pixel as i64) % w, (pixel as i64) / w);
    (-1..=1)
        .flat_map(move |dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
        .filter(move |&(qx, qy)| qx >= 0 && qy >= 0 && qx < w && qy < h)
        .map(move |(qx, qy)| (qy * w + qx) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pattern_is_stratified_on_both_axes_and_inside_the_square() {
        let p = pattern();
        for axis in [0, 1] {
            let mut cells: Vec<usize> = p.iter().map(|u| (u[axis] * SAMPLES as f32) as usize).collect();
            cells.sort();
            assert_eq!(cells, (0..SAMPLES).collect::<Vec<_>>(), "one sample per 1/{SAMPLES} on axis {axis}: {p:?}");
        }
        assert!(p.iter().all(|u| u.min_element() > 0.0 && u.max_element() < 1.0));
    }

    #[test]
    fn the_majority_id_covers_most_and_ties_go_to_the_lowest() {
        assert_eq!(majority_id(&[3, 5, 5, 3, 5], &[0.2; 5]), 5);
        assert_eq!(majority_id(&[7, 2, 2, 7], &[0.25; 4]), 2);
        assert_eq!(majority_id(&[NO_SURFACE, NO_SURFACE, 4], &[0.3, 0.3, 0.4]), NO_SURFACE);
        assert_eq!(majority_id(&[3, 5, 5, 5], &[0.7, 0.1, 0.1, 0.1]), 3, "by what they cover, not how many");
    }
}
