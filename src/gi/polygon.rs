//! Convex polygons: a triangle clipped to a cell, split by a plane, its area and centroid, the point of it
//! nearest another (the radiance cache's pieces, `entries`).

use glam::{UVec3, Vec3, Vec4};

use super::entries::MARGIN;
use super::grid::Grid;
use crate::scene::closest_on_triangle;

/// A convex polygon of at most 9 vertices: a triangle clipped by the 6 planes of a box.
#[derive(Clone, Copy, Debug)]
pub struct Polygon {
    pub(super) v: [Vec3; 9],
    pub(super) len: usize,
}

impl Polygon {
    pub(super) fn triangle(v: &[Vec3; 3]) -> Self {
        let mut p = Self { v: [Vec3::ZERO; 9], len: 3 };
        p.v[..3].copy_from_slice(v);
        p
    }

    /// Its part within cell `c` of `grid`, with the margin.
    pub(super) fn in_cell(self, grid: &Grid, c: UVec3) -> Self {
        let b = grid.cell_box(c);
        let margin = Vec3::splat(MARGIN * grid.cell);
        self.clipped(b.min - margin, b.max + margin)
    }

    /// Sutherland–Hodgman against the box `[lo, hi]`.
    pub(super) fn clipped(mut self, lo: Vec3, hi: Vec3) -> Self {
        for axis in 0..3 {
            let (mut min, mut max) = (Vec4::ZERO, Vec4::ZERO);
            min[axis] = 1.0;
            min.w = -lo[axis];
            max[axis] = -1.0;
            max.w = hi[axis];
            self = self.keep(min).keep(max);
            if self.len < 3 {
                break;
            }
        }
        self
    }

    /// The parts below and above `plane` (`plane · (p, 1) < 0` and `≥ 0`).
    pub(super) fn split(&self, plane: Vec4) -> [Self; 2] {
        [self.keep(-plane), self.keep(plane)]
    }

    /// The part where `plane · (p, 1) ≥ 0`.
    pub(super) fn keep(&self, plane: Vec4) -> Self {
        let mut out = Self { v: [Vec3::ZERO; 9], len: 0 };
        let distance = |p: Vec3| plane.truncate().dot(p) + plane.w;
        for i in 0..self.len {
            let (a, b) = (self.v[i], self.v[(i + 1) % self.len]);
            let (da, db) = (distance(a), distance(b));
            if da >= 0.0 {
                out.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                out.push(a + (b - a) * (da / (da - db)));
            }
        }
        out
    }

    pub(super) fn push(&mut self, p: Vec3) {
        if self.len < self.v.len() {
            self.v[self.len] = p;
            self.len += 1;
        }
    }

    /// Area and area-weighted centroid (the vertices' mean where the area is 0).
    pub(super) fn area_centroid(&self) -> (f32, Vec3) {
        if self.len < 3 {
            return (0.0, self.v[..self.len].iter().sum::<Vec3>() / self.len.max(1) as f32);
        }
        let (mut area, mut weighted) = (0.0, Vec3::ZERO);
        for i in 1..self.len - 1 {
            let (a, b, c) = (self.v[0], self.v[i], self.v[i + 1]);
            let t = 0.5 * (b - a).cross(c - a).length();
            area += t;
            weighted += t * (a + b + c) / 3.0;
        }
        if area > 0.0 {
            (area, weighted / area)
        } else {
            (0.0, self.v[..self.len].iter().sum::<Vec3>() / self.len as f32)
        }
    }

    /// Its point nearest `p`. Clipping leaves repeated and collinear corners, whose fan triangles have no
    /// area (the closest-point formulas divide by it): those count by their corners.
    pub(super) fn closest(&self, p: Vec3) -> Vec3 {
        let nearer = |a: &Vec3, b: &Vec3| a.distance_squared(p).total_cmp(&b.distance_squared(p));
        let corners = self.v[..self.len].iter().copied();
        (1..self.len.saturating_sub(1))
            .map(|i| closest_on_triangle(p, self.v[0], self.v[i], self.v[i + 1]))
            .filter(|q| q.is_finite())
            .chain(corners)
            .min_by(nearer)
            .unwrap_or(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    pub(super) fn a_clipped_square_keeps_the_area_inside_the_box() {
        let t = [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)];
        let p = Polygon::triangle(&t).clipped(Vec3::splat(-1.0), Vec3::ONE);
        let (area, centroid) = p.area_centroid();
        assert!((area - 1.0).abs() < 1e-6, "{area}: the unit square lies wholly under the hypotenuse");
        assert!((centroid - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
        let (whole, _) = Polygon::triangle(&t).area_centroid();
        assert!((whole - 2.0).abs() < 1e-6);
        assert!(Polygon::triangle(&t).clipped(Vec3::splat(3.0), Vec3::splat(4.0)).len < 3);
        let [below, above] = Polygon::triangle(&t).split(Vec4::new(1.0, 0.0, 0.0, -0.5));
        let (a, b) = (below.area_centroid().0, above.area_centroid().0);
        assert!((a + b - 2.0).abs() < 1e-6 && (b - 1.125).abs() < 1e-6, "{a} + {b}");
    }

    #[test]
    pub(super) fn the_closest_point_lies_on_the_triangle() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let inside = closest_on_triangle(Vec3::new(0.2, 0.2, 5.0), a, b, c);
        assert!((inside - Vec3::new(0.2, 0.2, 0.0)).length() < 1e-6, "{inside}");
        assert_eq!(closest_on_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c), a);
        let on_edge = closest_on_triangle(Vec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((on_edge - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
        // A clipped square with a repeated corner.
        let mut square = Polygon::triangle(&[a, a, b]);
        square.push(Vec3::new(1.0, 1.0, 0.0));
        square.push(c);
        let q = square.closest(Vec3::new(0.5, 0.5, 1.0));
        assert!((q - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6, "{q}");
    }
}
