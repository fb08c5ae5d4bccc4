//! Zoom views (docs/DESIGN.md §2): a square perspective view from a sensor that just holds a light group's
//! bounding box, so that the group's visibility is measured with a whole map's texels however small the
//! group looks. A 0.1 m light at 2 m covers a few texels of a hemicube's 64² face, and all of a zoom
//! view's.
//!
//! The view is drawn twice, with the whole scene and with the emitters alone; the ratio of the group's
//! weighted coverage in the two is its visibility (the reduction, `glsl/reduce.comp`).

use glam::{Mat4, Vec3};

use crate::scene::Aabb;
use crate::scene::camera::{projection, view_matrix};

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
    /// tan of half the field of view (of either side of the square).
    pub tan_half: f32,
}

impl Zoom {
    /// The narrowest square view from `origin` that holds every corner of `bounds`, widened by `margin`
    /// (relative, e.g. a texel's worth: `2 / rd`), turned so that its up axis is as close to `up_hint` as
    /// can be. `None` where the box lies wholly on or below the plane through `origin` with normal `n`: no
    /// part of the group is above the sensor's horizon, so it sends the sensor nothing.
    pub fn towards(origin: Vec3, n: Vec3, bounds: &Aabb, up_hint: Vec3, margin: f32) -> Option<Self> {
        let corners: Vec<Vec3> = (0..8)
            .map(|i| {
                let pick = |bit: u32, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
                Vec3::new(
                    pick(1, bounds.min.x, bounds.max.x),
                    pick(2, bounds.min.y, bounds.max.y),
                    pick(4, bounds.min.z, bounds.max.z),
                ) - origin
            })
            .collect();
        if corners.iter().all(|c| c.dot(n) <= 0.0) {
            return None;
        }
        let forward = corners.iter().map(|c| c.normalize_or_zero()).sum::<Vec3>().try_normalize().unwrap_or(n);
        let up = (up_hint - forward * up_hint.dot(forward))
            .try_normalize()
            .unwrap_or_else(|| forward.any_orthonormal_pair().1);
        let right = forward.cross(up);
        let min_cos = (1.0 / (1.0 + MAX_TAN_HALF * MAX_TAN_HALF)).sqrt();
        let mut tan_half = MIN_TAN_HALF;
        for c in &corners {
            let depth = c.dot(forward);
            if depth <= min_cos * c.length() {
                tan_half = MAX_TAN_HALF; // behind or beside the sensor: as wide as a view goes
                break;
            }
            tan_half = tan_half.max(c.dot(right).abs().max(c.dot(up).abs()) / depth);
        }
        Some(Self { forward, right, up, tan_half: (tan_half * (1.0 + margin)).min(MAX_TAN_HALF) })
    }

    /// World → Vulkan clip space of the view from `origin`: square, reversed-Z, infinite far plane, NDC y
    /// down (as every sensor view, `SensorFrame::view_proj`).
    pub fn view_proj(&self, origin: Vec3, near: f32) -> Mat4 {
        projection(2.0 * self.tan_half.atan(), 1.0, near) * view_matrix(origin, self.right, self.up, self.forward)
    }

    /// World direction (not unit) through the point `(ndc_x, ndc_y)` of the view (Vulkan NDC: y down): what
    /// the reduction computes a zoom texel's weight from.
    pub fn direction(&self, ndc_x: f32, ndc_y: f32) -> Vec3 {
        self.forward + self.right * (ndc_x * self.tan_half) - self.up * (ndc_y * self.tan_half)
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
        assert!(zoom.tan_half < 0.04, "a 0.1 box at 2 m is a few degrees wide: tan {}", zoom.tan_half);
        assert!(zoom.up.dot(Vec3::Z) > 0.9, "up follows the hint");
    }

    #[test]
    fn a_box_below_the_horizon_has_no_view_and_one_around_the_sensor_the_widest() {
        let bounds = Aabb { min: Vec3::new(-1.0, -2.0, -1.0), max: Vec3::new(1.0, -1.0, 1.0) };
        assert!(Zoom::towards(Vec3::ZERO, Vec3::Y, &bounds, Vec3::Z, 0.0).is_none());
        let around = Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        assert_eq!(Zoom::towards(Vec3::ZERO, Vec3::Y, &around, Vec3::Z, 0.0).unwrap().tan_half, MAX_TAN_HALF);
    }
}
