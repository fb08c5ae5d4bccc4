//! Zoom views (docs/DESIGN.md §2): a perspective view from a sensor that just holds a light group's
//! bounding box, so that the group's visibility is measured with a whole map's texels however small the
//! group looks. A 0.1 m light at 2 m covers a few texels of a hemicube's 64² face, and all of a zoom
//! view's. The view is a rectangle along the box's projection's principal axes: a ceiling light seen from
//! just below its plane is a sliver, which a square view would cover with less than a texel row (and a
//! group no texel covers counts as unoccluded: it leaked through walls); a rectangle spreads it over
//! every row.
//!
//! The view is drawn twice, with the whole scene and with the emitters alone; the ratio of the group's
//! weighted coverage in the two is its visibility (the reduction, `glsl/reduce.comp`).

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::scene::Aabb;
use crate::scene::camera::view_matrix;

/// The widest zoom view: tan 80°. A box that wraps around a sensor further than that (the sensor sits
/// nearly on its group) is measured over the central 160° only.
pub const MAX_TAN_HALF: f32 = 5.671_282;

/// The narrowest zoom view: a box seen edge-on or from afar still gets a view of finite size.
pub const MIN_TAN_HALF: f32 = 1e-4;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Zoom {
    /// Right-handed unit axes of the view, as a camera: `right = forward × up`.
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// tan of half the field of view along `right` (x) and `up` (y).
    pub tan_half: Vec2,
}

impl Zoom {
    /// The plane `(m, d)` (keeping `m·p + d ≥ 0`) beyond which, along this view's forward axis from
    /// `origin`, nothing can stand between `origin` and a point of `bounds`: past its farthest corner, with
    /// `margin` (world units) to spare.
    pub fn far_plane(&self, origin: Vec3, bounds: &Aabb, margin: f32) -> Vec4 {
        let far = bounds.corners().iter().map(|&c| self.forward.dot(c - origin)).fold(f32::MIN, f32::max);
        let far = far + margin + 1e-4 * far.abs();
        (-self.forward).extend(self.forward.dot(origin) + far)
    }

    /// The narrowest view from `origin` that holds every corner of `bounds`, widened by `margin` (relative,
    /// e.g. a texel's worth: `2 / rd`), its right axis along the major axis of the corners' projection (its
    /// up axis, where that projection is round, as close to `up_hint` as can be). `None` where the box lies
    /// wholly on or below the plane through `origin` with normal `n`: no part of the group is above the
    /// sensor's horizon, so it sends the sensor nothing.
    pub fn towards(origin: Vec3, n: Vec3, bounds: &Aabb, up_hint: Vec3, margin: f32) -> Option<Self> {
        let corners = bounds.corners().map(|c| c - origin);
        if corners.iter().all(|c| c.dot(n) <= 0.0) {
            return None;
        }
        let forward = corners.iter().map(|c| c.normalize_or_zero()).sum::<Vec3>().try_normalize().unwrap_or(n);
        let up0 = (up_hint - forward * up_hint.dot(forward))
            .try_normalize()
            .unwrap_or_else(|| forward.any_orthonormal_pair().1);
        let right0 = forward.cross(up0);
        let min_cos = (1.0 / (1.0 + MAX_TAN_HALF * MAX_TAN_HALF)).sqrt();
        if corners.iter().any(|c| c.dot(forward) <= min_cos * c.length()) {
            // Behind or beside the sensor: as wide as a view goes.
            return Some(Self { forward, right: right0, up: up0, tan_half: Vec2::splat(MAX_TAN_HALF) });
        }
        // The corners on the view plane at distance 1, and their principal axes (about the view's centre).
        let plane: Vec<Vec2> = corners.iter().map(|c| Vec2::new(c.dot(right0), c.dot(up0)) / c.dot(forward)).collect();
        let (sxx, syy, sxy) =
            plane.iter().fold((0.0, 0.0, 0.0), |(a, b, c), p| (a + p.x * p.x, b + p.y * p.y, c + p.x * p.y));
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let (sin, cos) = angle.sin_cos();
        let right = right0 * cos + up0 * sin;
        let up = up0 * cos - right0 * sin;
        let mut tan_half = Vec2::splat(MIN_TAN_HALF);
        for c in &corners {
            let depth = c.dot(forward);
            tan_half = tan_half.max(Vec2::new(c.dot(right).abs(), c.dot(up).abs()) / depth);
        }
        let tan_half = (tan_half * (1.0 + margin)).min(Vec2::splat(MAX_TAN_HALF));
        Some(Self { forward, right, up, tan_half })
    }

    /// World → Vulkan clip space of the view from `origin`: reversed-Z, infinite far plane, NDC y down (as
    /// every sensor view, `SensorFrame::view_proj`; `scene::camera::projection` with both tangents given).
    pub fn view_proj(&self, origin: Vec3, near: f32) -> Mat4 {
        let t = self.tan_half;
        let projection = Mat4::from_cols(
            Vec4::new(1.0 / t.x, 0.0, 0.0, 0.0),
            Vec4::new(0.0, -1.0 / t.y, 0.0, 0.0),
            Vec4::new(0.0, 0.0, 0.0, -1.0),
            Vec4::new(0.0, 0.0, near, 0.0),
        );
        projection * view_matrix(origin, self.right, self.up, self.forward)
    }

    /// World direction (not unit) through the point `(ndc_x, ndc_y)` of the view (Vulkan NDC: y down): what
    /// the reduction computes a zoom texel's weight from.
    pub fn direction(&self, ndc_x: f32, ndc_y: f32) -> Vec3 {
        self.forward + self.right * (ndc_x * self.tan_half.x) - self.up * (ndc_y * self.tan_half.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ndc(m: Mat4, p: Vec3) -> (f32, f32, f32) {
        let c = m * p.extend(1.0);
        (c.x / c.w, c.y / c.w, c.w)
    }

    #[test]
    fn the_view_holds_every_corner_and_its_directions_match_its_projection() {
        let origin = Vec3::new(0.3, 0.0, -0.2);
        let bounds = Aabb { min: Vec3::new(-0.05, 2.0, -0.05), max: Vec3::new(0.05, 2.001, 0.05) };
        let zoom = Zoom::towards(origin, Vec3::Y, &bounds, Vec3::Z, 0.0).unwrap();
        let m = zoom.view_proj(origin, 1e-3);
        let mut widest: f32 = 0.0;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { bounds.min.x } else { bounds.max.x },
                if i & 2 == 0 { bounds.min.y } else { bounds.max.y },
                if i & 4 == 0 { bounds.min.z } else { bounds.max.z },
            );
            let (x, y, w) = ndc(m, corner);
            assert!(w > 0.0 && x.abs() <= 1.0 + 1e-4 && y.abs() <= 1.0 + 1e-4, "corner {corner} at ({x}, {y})");
            widest = widest.max(x.abs()).max(y.abs());
            // The direction through that NDC point leads back to the corner.
            let d = zoom.direction(x, y);
            assert!(d.normalize().dot((corner - origin).normalize()) > 1.0 - 1e-6);
        }
        assert!(widest > 0.99, "the narrowest view: a corner on its edge ({widest})");
        assert!(zoom.tan_half.max_element() < 0.04, "a 0.1 box at 2 m is a few degrees wide: tan {}", zoom.tan_half);
        assert!(zoom.right.cross(zoom.up).dot(zoom.forward) < -0.999, "right-handed: right = forward × up");
    }

    /// A ceiling light seen from just below its plane fills the view's rows: the view is a rectangle along
    /// the sliver, each of its sides holding a corner.
    #[test]
    fn a_light_seen_nearly_edge_on_fills_a_rectangle() {
        let bounds = Aabb { min: Vec3::new(0.7, 1.99, -0.3), max: Vec3::new(1.3, 1.99, 0.3) };
        let origin = Vec3::new(-0.4, 1.985, 1.0);
        let zoom = Zoom::towards(origin, -Vec3::Z, &bounds, Vec3::Y, 0.0).unwrap();
        let (tx, ty) = (zoom.tan_half.x, zoom.tan_half.y);
        assert!(tx.min(ty) < 0.05 * tx.max(ty), "a sliver: tan {tx} × {ty}");
        let m = zoom.view_proj(origin, 1e-3);
        let (mut widest_x, mut widest_y) = (0.0f32, 0.0f32);
        for x in [bounds.min.x, bounds.max.x] {
            for z in [bounds.min.z, bounds.max.z] {
                let (px, py, w) = ndc(m, Vec3::new(x, 1.99, z));
                assert!(w > 0.0 && px.abs() <= 1.0 + 1e-4 && py.abs() <= 1.0 + 1e-4, "({px}, {py})");
                (widest_x, widest_y) = (widest_x.max(px.abs()), widest_y.max(py.abs()));
                let d = zoom.direction(px, py);
                assert!(d.normalize().dot((Vec3::new(x, 1.99, z) - origin).normalize()) > 1.0 - 1e-6);
            }
        }
        assert!(widest_x > 0.99 && widest_y > 0.99, "both sides held tight: {widest_x}, {widest_y}");
    }

    #[test]
    fn a_box_below_the_horizon_has_no_view_and_one_around_the_sensor_the_widest() {
        let bounds = Aabb { min: Vec3::new(-1.0, -2.0, -1.0), max: Vec3::new(1.0, -1.0, 1.0) };
        assert!(Zoom::towards(Vec3::ZERO, Vec3::Y, &bounds, Vec3::Z, 0.0).is_none());
        let around = Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        assert_eq!(
            Zoom::towards(Vec3::ZERO, Vec3::Y, &around, Vec3::Z, 0.0).unwrap().tan_half,
            Vec2::splat(MAX_TAN_HALF)
        );
    }
}
