//! How much of a supersampled pixel's square each surface covers (step 2 of `supersample`), counted with a
//! net of [`COVERAGE_RAYS`] camera rays that only ask which surface they meet, so that the
//! [`SAMPLES`] shaded samples weigh what their surface covers rather than 1/[`SAMPLES`] each.
//!
//! A dark face with a bright surface's edge across 1 % of its square (the table top's lit top seen above
//! its front, which the light is behind) is 1 % as bright as that surface: with 64 samples its value is 0
//! or 1/64 of it, 100 % or 60 % off a dim pixel, and such pixels were a third of the small light's error
//! over the whole image. The net counts each surface's share in 1/1024ths; the samples of a surface share
//! its count; a surface the net meets and no sample does takes a sample from the surface with most
//! (at the net's ray nearest the middle of that surface's rays), so that every surface the square shows is
//! shaded.
//!
//! ```text
//!   square, net of 1 024 rays        64 samples                  weights
//!   ┌──────────────┐                 ┌──────────────┐
//!   │▓ 1.3 % lit   │                 │  · · · · ·   │             lit: 0.013 / 1 (one sample moved there)
//!   │ dark face    │      ──►        │ · · dark · · │  ──►        dark: 0.987 / 63 each
//!   └──────────────┘                 └──────────────┘
//! ```

use glam::Vec2;
use rayon::prelude::*;

use super::{SAMPLES, Samples, neighbourhood};
use crate::gbuffer::GBufferData;
use crate::gbuffer::cast::cast_points;
use crate::scene::bvh::Bvh;
use crate::scene::{ImageSize, NO_SURFACE, Scene};

/// Id-only camera rays per supersampled pixel that count what each surface covers: a pixel's shares are
/// within 1/1 024 of its square on a straight edge (a (0, 2)-net: every strip of the square 1/1 024 wide
/// or tall holds one). Measured on the small light at 320 × 240 (direct light) against the pixel-area
/// oracle: docs/ACCURACY.md "Every pixel right".
pub const COVERAGE_RAYS: usize = 1024;

/// Point `j` of the coverage net in [0, 1)²: x stratified in 1 024ths, y the base-2 radical inverse.
fn net(j: usize) -> Vec2 {
    let y = (j as u32).reverse_bits() as f32 / 2f32.powi(32);
    Vec2::new((j as f32 + 0.5) / COVERAGE_RAYS as f32, y + 0.5 / COVERAGE_RAYS as f32)
}

/// What a ray meets, as coverage tells surfaces apart: the surface id and whether its front is seen
/// (`NO_SURFACE`, false where it leaves the scene).
type Class = (u32, bool);

/// One pixel's net: the rays each class met, and the samples moved to a class no sample met (the
/// sample's index, its new image point).
#[derive(Default)]
struct PixelCoverage {
    counts: Vec<(Class, usize)>,
    moves: Vec<(usize, Vec2)>,
}

/// The samples of `pixels` (of the image whose centres `g` holds), [`SAMPLES`] each: `seen` at `points`,
/// weighed by the coverage net where the pixel's samples or the centres of its 3 × 3 neighbourhood show
/// more than one surface (elsewhere, a shadow's edge on one surface, alike); a sample is moved where a
/// surface the net meets has none (and cast again there).
pub fn weigh(
    (scene, bvh, g): (&Scene, &Bvh, &GBufferData),
    pixels: &[u32],
    mut seen: GBufferData,
    mut points: Vec<Vec2>,
) -> Samples {
    let per_pixel: Vec<PixelCoverage> = (pixels.par_iter().enumerate())
        .map(|(n, &pixel)| {
            let range = n * SAMPLES..(n + 1) * SAMPLES;
            let classes: Vec<Class> = range.clone().map(|s| class_of(&seen, s)).collect();
            let centres = neighbourhood(g.size, pixel).map(|q| class_of(g, q));
            if classes.iter().copied().chain(centres).all(|c| c == classes[0]) {
                return PixelCoverage::default();
            }
            cover((scene, bvh, g.size), pixel, classes, (&points[range.clone()], range.start))
        })
        .collect();
    let moved: Vec<(usize, Vec2)> = per_pixel.iter().flat_map(|p| p.moves.iter().copied()).collect();
    let recast = cast_points(scene, bvh, g.size, &moved.iter().map(|&(_, at)| at).collect::<Vec<_>>());
    for (r, &(s, at)) in moved.iter().enumerate() {
        points[s] = at;
        seen.position[s] = recast.position[r];
        seen.normal[s] = recast.normal[r];
        seen.albedo[s] = recast.albedo[r];
        seen.emission[s] = recast.emission[r];
        seen.surface[s] = recast.surface[r];
    }
    let weights = (per_pixel.iter().enumerate())
        .flat_map(|(n, p)| {
            let classes: Vec<Class> = (n * SAMPLES..(n + 1) * SAMPLES).map(|s| class_of(&seen, s)).collect();
            let count = |c: &Class| p.counts.iter().find(|(k, _)| k == c).map_or(0, |(_, n)| *n);
            // Only the classes some sample shows share the square (all of it but in a pixel of more than
            // SAMPLES surfaces); none where the net was not cast.
            let total: usize = p.counts.iter().filter(|(c, _)| classes.contains(c)).map(|(_, n)| n).sum();
            let of = |c: &Class| classes.iter().filter(|&o| o == c).count() as f32;
            let weights: Vec<f32> = (classes.iter())
                .map(|c| if total == 0 { 1.0 / SAMPLES as f32 } else { count(c) as f32 / total as f32 / of(c) })
                .collect();
            weights
        })
        .collect();
    Samples { seen, points, weights }
}

/// The class of what `g`'s sample `s` shows.
fn class_of(g: &GBufferData, s: usize) -> Class {
    (g.surface[s], g.normal[s].w > 0.5)
}

/// Casts the net over `pixel` (its samples show `classes`, at `points`, the first of them sample `first`):
/// each class's count; for each class the net meets and no sample does (most covered first), the net's
/// ray of that class nearest the middle of its rays takes the nearest sample of the class with most
/// samples, if it has two or more.
fn cover(
    (scene, bvh, size): (&Scene, &Bvh, ImageSize),
    pixel: u32,
    mut classes: Vec<Class>,
    (points, first): (&[Vec2], usize),
) -> PixelCoverage {
    let corner = Vec2::new((pixel % size.width) as f32, (pixel / size.width) as f32);
    let class = |at: Vec2| -> Class {
        let ray = scene.camera.ray(at.x, at.y, size.width, size.height);
        bvh.intersect(&ray, 0.0, f32::INFINITY).map_or((NO_SURFACE, false), |hit| {
            let tri = &scene.mesh.triangles[hit.triangle as usize];
            (tri.surface, ray.dir.dot(tri.normal) < 0.0)
        })
    };
    let rays: Vec<(Vec2, Class)> = (0..COVERAGE_RAYS).map(|j| corner + net(j)).map(|at| (at, class(at))).collect();
    // Each class: its count and the sum of its rays' points.
    let mut counts: Vec<(Class, usize, Vec2)> = Vec::new();
    for &(at, c) in &rays {
        match counts.iter_mut().find(|(k, _, _)| *k == c) {
            Some((_, count, sum)) => (*count, *sum) = (*count + 1, *sum + at),
            None => counts.push((c, 1, at)),
        }
    }
    let mut missing: Vec<&(Class, usize, Vec2)> = counts.iter().filter(|(c, _, _)| !classes.contains(c)).collect();
    missing.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let distance = |a: Vec2, b: Vec2| (a - b).length_squared();
    let mut moves = Vec::new();
    for &(c, count, sum) in missing {
        let middle = sum / count as f32;
        let to = (rays.iter().filter(|(_, k)| *k == c).map(|(at, _)| *at))
            .min_by(|a, b| distance(*a, middle).total_cmp(&distance(*b, middle)));
        let most = (classes.iter())
            .map(|k| (classes.iter().filter(|&o| o == k).count(), *k))
            .max_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1)));
        let (Some(to), Some((many, from))) = (to, most) else { continue };
        if many < 2 {
            continue;
        }
        let k = (0..SAMPLES)
            .filter(|&k| classes[k] == from)
            .min_by(|&a, &b| distance(points[a], to).total_cmp(&distance(points[b], to)))
            .expect("the class has samples");
        classes[k] = c;
        moves.push((first + k, to));
    }
    PixelCoverage { counts: counts.into_iter().map(|(c, count, _)| (c, count)).collect(), moves }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_net_is_stratified_on_both_axes_and_inside_the_square() {
        for axis in [0, 1] {
            let mut cells: Vec<usize> =
                (0..COVERAGE_RAYS).map(|j| (net(j)[axis] * COVERAGE_RAYS as f32) as usize).collect();
            cells.sort();
            assert_eq!(cells, (0..COVERAGE_RAYS).collect::<Vec<_>>(), "one ray per 1/{COVERAGE_RAYS} on axis {axis}");
        }
    }
}
