//! The light a supersampled pixel's square emits, exactly: each emitter triangle's front clipped to the
//! square on screen, times its `Ke` and the share of it nothing hides. An emitter is hundreds of times
//! brighter than what it lights (17 against 0.03 on the Cornell box's ceiling), so a pixel on its rim that
//! samples its coverage in steps of 1/SAMPLES is tens of percent off; the clipped area has no such step.
//! An emission-textured triangle's part in the square emits its texture's mean over that part, taken at
//! points spread over it on screen and carried back onto the triangle.

use glam::{Vec2, Vec3, Vec4};

use crate::gbuffer::cast::first_surface;
use crate::scene::bvh::Bvh;
use crate::scene::{ImageSize, Scene, SurfaceId};

/// An emitter triangle's front as the camera sees it.
pub struct ScreenEmitter {
    /// Vertices in continuous pixel coordinates.
    v: [Vec2; 3],
    surface: SurfaceId,
    /// Its index in the mesh.
    triangle: usize,
    /// Its radiance, where constant (no emission texture).
    ke: Option<Vec3>,
}

/// The emitter triangles whose front faces the camera at `eye`, on screen; and the emitting surfaces that
/// could not be projected (a vertex behind the camera), whose light the samples measure instead.
pub fn screen_emitters(scene: &Scene, size: ImageSize) -> (Vec<ScreenEmitter>, Vec<SurfaceId>) {
    let (mut emitters, mut sampled) = (Vec::new(), Vec::new());
    for (i, t) in scene.mesh.triangles.iter().enumerate() {
        let material = scene.mesh.material_of(t.surface);
        if !material.is_emitter() || (scene.camera.eye - t.v[0]).dot(t.normal) <= 0.0 {
            continue;
        }
        let projected: Option<Vec<Vec2>> =
            t.v.iter().map(|&v| scene.camera.project(v, size.width, size.height)).collect();
        match projected {
            Some(p) => emitters.push(ScreenEmitter {
                v: [p[0], p[1], p[2]],
                surface: t.surface,
                triangle: i,
                ke: (!scene.mesh.emits_textured(i)).then_some(material.ke),
            }),
            None => sampled.push(t.surface),
        }
    }
    emitters.retain(|e| !sampled.contains(&e.surface));
    (emitters, sampled)
}

/// The mean radiance the square of pixel (x, y) emits: each of `emitters` clipped to it, weighed by the
/// share of its part that is seen (of the pixel's samples, which see `surface` and `emission` at the image
/// points `points`, those that fall inside it,
/// those that meet its surface's front; where none falls inside, a ray through the part's centroid
/// decides); plus the samples' own emission on the surfaces in `sampled`.
pub fn emitted(
    (scene, bvh, size): (&Scene, &Bvh, ImageSize),
    (emitters, sampled): (&[ScreenEmitter], &[SurfaceId]),
    (x, y): (u32, u32),
    (surface, emission, points): (&[SurfaceId], &[Vec4], &[Vec2]),
) -> Vec3 {
    let square =
        [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(dx, dy)| Vec2::new(x as f32 + dx, y as f32 + dy));
    let mut sum = Vec3::ZERO;
    for e in emitters {
        let (lo, hi) = (e.v[0].min(e.v[1]).min(e.v[2]), e.v[0].max(e.v[1]).max(e.v[2]));
        if hi.x <= square[0].x || hi.y <= square[0].y || lo.x >= square[2].x || lo.y >= square[2].y {
            continue;
        }
        let part = clip(&square, &e.v);
        let area = polygon_area(&part);
        if area <= 0.0 {
            continue;
        }
        let inside: Vec<usize> = (0..points.len()).filter(|&k| inside_triangle(points[k], &e.v)).collect();
        let seen = if inside.is_empty() {
            let centroid = part.iter().sum::<Vec2>() / part.len() as f32;
            let ray = scene.camera.ray(centroid.x, centroid.y, size.width, size.height);
            first_surface(scene, bvh, &ray)
                .is_some_and(|v| v.surface == e.surface && v.emission.truncate() != Vec3::ZERO) as u32
                as f32
        } else {
            let meets = |k: &&usize| surface[**k] == e.surface && emission[**k].truncate() != Vec3::ZERO;
            inside.iter().filter(meets).count() as f32 / inside.len() as f32
        };
        let radiance = e.ke.unwrap_or_else(|| mean_radiance((scene, size), e.triangle, &part));
        sum += radiance * area * seen;
    }
    let on_sampled = (0..surface.len()).filter(|&k| sampled.contains(&surface[k]));
    sum + on_sampled.map(|k| emission[k].truncate()).sum::<Vec3>() / surface.len().max(1) as f32
}

/// The mean radiance emission-textured triangle `triangle` emits over `part`, a convex polygon of its
/// projection on screen: its fan triangles' [`crate::scene::subdivision_centroids`], 16 each, carried back
/// onto the triangle's plane along their camera rays, weighed by the fan triangles' areas.
fn mean_radiance((scene, size): (&Scene, ImageSize), triangle: usize, part: &[Vec2]) -> Vec3 {
    let t = &scene.mesh.triangles[triangle];
    let (mut sum, mut area) = (Vec3::ZERO, 0.0);
    for k in 1..part.len().saturating_sub(1) {
        let fan = [part[0], part[k], part[k + 1]];
        let fan_area = polygon_area(&fan);
        let points: Vec<Vec2> =
            crate::scene::subdivision_centroids(4).map(|b| crate::scene::at_barycentric(&fan, b)).collect();
        for s in &points {
            let ray = scene.camera.ray(s.x, s.y, size.width, size.height);
            let along = (t.v[0] - ray.origin).dot(t.normal) / ray.dir.dot(t.normal);
            let at = if along.is_finite() { ray.at(along) } else { t.v[0] };
            sum += scene.mesh.emission_at(triangle, at) * (fan_area / points.len() as f32);
        }
        area += fan_area;
    }
    if area > 0.0 { sum / area } else { scene.mesh.mean_emission(triangle) }
}

/// The convex polygon `square` clipped to the triangle `t` (Sutherland–Hodgman; either winding).
fn clip(square: &[Vec2; 4], t: &[Vec2; 3]) -> Vec<Vec2> {
    let cross = |a: Vec2, b: Vec2| a.x * b.y - a.y * b.x;
    let sign = if cross(t[1] - t[0], t[2] - t[0]) < 0.0 { -1.0 } else { 1.0 };
    let mut polygon = square.to_vec();
    for k in 0..3 {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        let side = |p: Vec2| sign * cross(b - a, p - a);
        let mut out = Vec::with_capacity(polygon.len() + 1);
        for i in 0..polygon.len() {
            let (p, q) = (polygon[i], polygon[(i + 1) % polygon.len()]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                out.push(p + (q - p) * (sp / (sp - sq)));
            }
        }
        polygon = out;
        if polygon.is_empty() {
            break;
        }
    }
    polygon
}

fn polygon_area(p: &[Vec2]) -> f32 {
    let twice: f32 = (0..p.len()).map(|i| p[i].x * p[(i + 1) % p.len()].y - p[(i + 1) % p.len()].x * p[i].y).sum();
    0.5 * twice.abs()
}

fn inside_triangle(p: Vec2, t: &[Vec2; 3]) -> bool {
    let cross = |a: Vec2, b: Vec2| a.x * b.y - a.y * b.x;
    let s = [0, 1, 2].map(|k| cross(t[(k + 1) % 3] - t[k], p - t[k]));
    s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_clipped_to_a_pixel_has_the_area_it_covers() {
        let square = [Vec2::new(2.0, 3.0), Vec2::new(3.0, 3.0), Vec2::new(3.0, 4.0), Vec2::new(2.0, 4.0)];
        // Half the square below its diagonal, in both windings.
        let t = [Vec2::new(2.0, 3.0), Vec2::new(3.0, 3.0), Vec2::new(3.0, 4.0)];
        assert!((polygon_area(&clip(&square, &t)) - 0.5).abs() < 1e-6);
        let reversed = [t[2], t[1], t[0]];
        assert!((polygon_area(&clip(&square, &reversed)) - 0.5).abs() < 1e-6);
        // A sliver 0.2 tall crossing the whole square: 0.2 of it.
        let sliver = [Vec2::new(0.0, 3.4), Vec2::new(10.0, 3.4), Vec2::new(10.0, 3.6)];
        let wide = [sliver[0], sliver[2], Vec2::new(0.0, 3.6)];
        let area = polygon_area(&clip(&square, &sliver)) + polygon_area(&clip(&square, &wide));
        assert!((area - 0.2).abs() < 1e-5, "{area}");
        let far = [Vec2::new(10.0, 10.0), Vec2::new(11.0, 10.0), Vec2::new(10.0, 11.0)];
        assert_eq!(polygon_area(&clip(&square, &far)), 0.0);
    }
}
