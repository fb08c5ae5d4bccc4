//! Geometry the scene is made of and every layer computes with: triangles and their surfaces' ids, boxes,
//! barycentric coordinates, subdivisions and stratified points.

use glam::{Vec2, Vec3};

/// Surface ids are 1-based; 0 marks "no surface" (the background) in the G-buffer.
pub type SurfaceId = u32;
pub const NO_SURFACE: SurfaceId = 0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Counter-clockwise seen from the front.
    pub v: [Vec3; 3],
    /// Unit normal of the front side: normalize((v1 − v0) × (v2 − v0)).
    pub normal: Vec3,
    pub surface: SurfaceId,
}

/// The point of triangle `abc` nearest `p` (Ericson, *Real-Time Collision Detection* §5.1.5).
pub fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Self = Self { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(self, other: Self) -> Self {
        Self { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The box of `points` ([`Aabb::EMPTY`] for none).
    pub fn of(points: impl IntoIterator<Item = Vec3>) -> Self {
        let mut b = Self::EMPTY;
        points.into_iter().for_each(|p| b.grow(p));
        b
    }

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    /// Whether it holds `other`.
    pub fn contains(&self, other: &Self) -> bool {
        self.min.cmple(other.min).all() && other.max.cmple(self.max).all()
    }

    /// The distance from `p` to its nearest point (0 inside). Where one box holds another, this is never
    /// larger for it, in floating point too (every step is monotonic).
    pub fn distance(&self, p: Vec3) -> f32 {
        (self.min - p).max(p - self.max).max(Vec3::ZERO).length()
    }

    /// The distance from `p` to its farthest point.
    pub fn farthest(&self, p: Vec3) -> f32 {
        (p - self.min).abs().max((p - self.max).abs()).length()
    }

    /// Its eight corners: bit 0 of the index picks x's max, bit 1 y's, bit 2 z's.
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            let pick = |bit: usize, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
            Vec3::new(pick(1, self.min.x, self.max.x), pick(2, self.min.y, self.max.y), pick(4, self.min.z, self.max.z))
        })
    }
}

/// The corners' `values` of triangle `v` (shading normals, texture coordinates) interpolated at `p` by its
/// [`barycentric`] coordinates.
pub fn interpolate<T>(v: &[Vec3; 3], values: &[T; 3], p: Vec3) -> T
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let [b0, b1, b2] = barycentric(v, p);
    values[0] * b0 + values[1] * b1 + values[2] * b2
}

/// The point of barycentric coordinates `(b.x, b.y)` (the weights of corners 1 and 2) among `values`.
pub fn at_barycentric<T>(values: &[T; 3], b: Vec2) -> T
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    values[0] * (1.0 - b.x - b.y) + values[1] * b.x + values[2] * b.y
}

/// A triangle's k × k subdivision: k² congruent triangles, each as its corners' barycentric coordinates
/// (weights of corners 1 and 2), counter-clockwise as the triangle is; together they tile it.
///
/// ```text
///   corner 2
///     |\
///     |\|\        k = 3: the upright triangles at (a, b), a + b < k, and the
///     |\|\|\       inverted ones between them, a + b + 1 < k
///   corner 0 ── corner 1
/// ```
pub fn subdivision(k: usize) -> impl Iterator<Item = [Vec2; 3]> {
    let s = 1.0 / k as f32;
    (0..k).flat_map(move |a| {
        (0..k - a).flat_map(move |b| {
            let at = |i: usize, j: usize| Vec2::new(i as f32 * s, j as f32 * s);
            let upright = [at(a, b), at(a + 1, b), at(a, b + 1)];
            let inverted = [at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)];
            std::iter::once(upright).chain((a + b + 1 < k).then_some(inverted))
        })
    })
}

/// The centroids of [`subdivision`]`(k)`'s parts, as barycentric coordinates: k² points spread evenly over
/// a triangle, each standing for an equal share of its area.
pub fn subdivision_centroids(k: usize) -> impl Iterator<Item = Vec2> {
    subdivision(k).map(|part| (part[0] + part[1] + part[2]) / 3.0)
}

/// The barycentric coordinates of `p` (on or near the triangle `v`'s plane), each clamped to the
/// triangle so that a point just off an edge takes the edge's.
pub fn barycentric(v: &[Vec3; 3], p: Vec3) -> [f32; 3] {
    let (e1, e2, d) = (v[1] - v[0], v[2] - v[0], p - v[0]);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let (b1, b2) = ((d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det);
    let b = [1.0 - b1 - b2, b1, b2].map(|x| x.max(0.0));
    let sum = b[0] + b[1] + b[2];
    b.map(|x| x / sum)
}

/// The area of triangle `v`.
pub fn triangle_area(v: &[Vec3; 3]) -> f32 {
    0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length()
}

/// Point `k` of `count` spread over triangles of `areas` (their sum `total` > 0), stratified by area: the
/// triangle holding the (k + ½)/count quantile of the area, and where in it, barycentric `(u, v)` of an R2
/// point folded into the triangle. Deterministic; the lights' hint points and the radiance cache's spread
/// points.
pub fn stratified_point(areas: &[f32], total: f32, k: usize, count: usize) -> (usize, f32, f32) {
    let mut target = (k as f32 + 0.5) / count as f32 * total;
    let i = areas.iter().position(|&a| {
        target -= a;
        target <= 0.0
    });
    let (mut u, mut v) = ((0.5 + 0.754_877_7 * k as f32).fract(), (0.5 + 0.569_840_3 * k as f32).fract());
    if u + v > 1.0 {
        (u, v) = (1.0 - u, 1.0 - v);
    }
    (i.unwrap_or(areas.len() - 1), u, v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_boxs_corners_are_every_mix_of_its_bounds() {
        let b = Aabb { min: Vec3::new(-1.0, 2.0, 3.0), max: Vec3::new(4.0, 5.0, 6.0) };
        let c = b.corners();
        assert_eq!((c[0], c[7]), (b.min, b.max));
        assert_eq!(c[1], Vec3::new(4.0, 2.0, 3.0), "bit 0: x's max");
        assert_eq!(c[6], Vec3::new(-1.0, 5.0, 6.0), "bits 1 and 2: y's and z's max");
        assert_eq!(Aabb::of(c), b);
    }

    /// k × k congruent parts, counter-clockwise as the triangle is, that tile it: their areas sum to its
    /// area and their centroids are distinct.
    #[test]
    fn a_subdivision_tiles_the_triangle() {
        for k in [1, 2, 3, 6] {
            let parts: Vec<[Vec2; 3]> = subdivision(k).collect();
            assert_eq!(parts.len(), k * k);
            let area = |p: &[Vec2; 3]| 0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0]);
            for p in &parts {
                assert!((area(p) - 0.5 / (k * k) as f32).abs() < 1e-6, "k {k}: {p:?} is not k² times smaller");
                assert!(p.iter().all(|b| b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6), "{p:?} outside");
            }
            let mut centroids: Vec<(i32, i32)> =
                parts.iter().map(|p| ((p[0] + p[1] + p[2]) * 1000.0 / 3.0).round().as_ivec2().into()).collect();
            centroids.sort_unstable();
            centroids.dedup();
            assert_eq!(centroids.len(), k * k, "k {k}: parts overlap");
        }
        let v = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert_eq!(at_barycentric(&v, Vec2::new(0.25, 0.5)), Vec3::new(0.25, 0.5, 0.0));
    }
}
