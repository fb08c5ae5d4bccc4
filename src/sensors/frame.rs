//! Where a sensor sits and how it is turned. One definition for the GPU views and the CPU reference, so both
//! integrate over the same domain: the paper's square frustum is not rotation-symmetric about `n`.

use glam::{Mat4, Vec3, Vec4};

use super::layout::{Axis, ViewLayout};
use crate::scene::camera::{projection, view_matrix};

/// Sensor offsets as fractions of the scene's diagonal (so they scale with the scene's units).
///
/// - `BIAS`: the sensor sits this far above its surface, along `n`, so that its own surface is never seen.
/// - `NEAR`: the near plane of its views. Reversed-Z with a float depth buffer keeps precision at any
///   distance, so it only has to be small against the room, not large for the depth buffer's sake.
pub const BIAS: f32 = 2e-4;
pub const NEAR: f32 = 1e-4;

/// [`BIAS`] and [`NEAR`] for a scene of diagonal `scale`: the sensors' lift and near plane in its units,
/// as the renderer, the light hints, the supersampling and the CPU oracle all use them.
pub fn offsets(scale: f32) -> (f32, f32) {
    (BIAS * scale, NEAR * scale)
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorFrame {
    pub origin: Vec3,
    /// Tangent, bitangent, normal: orthonormal and right-handed (`t × b = n`).
    pub t: Vec3,
    pub b: Vec3,
    pub n: Vec3,
}

impl SensorFrame {
    /// The sensor for the surface point `p` with unit normal `n` (facing the viewer), lifted by `bias`.
    ///
    /// The tangents come from Duff et al. 2017 ("Building an orthonormal basis, revisited"), continuous in `n`
    /// except across `n.z = 0`; −0 is folded onto +0 so that one wall gets one frame.
    pub fn new(p: Vec3, n: Vec3, bias: f32) -> Self {
        let n = n + Vec3::ZERO; // −0.0 + 0.0 = +0.0
        let (t, b) = n.any_orthonormal_pair();
        Self { origin: p + n * bias, t, b, n }
    }

    /// The same sensor turned about its normal by `angle` radians. A hemicube covers the same hemisphere
    /// whatever its turn, so this changes only which directions share a texel: turning each pixel's sensor
    /// differently ([`pixel_turn`]) makes what aliasing remains noise, which the filter removes, instead of
    /// bands.
    pub fn turned(self, angle: f32) -> Self {
        let (sin, cos) = angle.sin_cos();
        Self { t: self.t * cos + self.b * sin, b: self.b * cos - self.t * sin, ..self }
    }

    pub fn axis(&self, axis: Axis) -> Vec3 {
        match axis {
            Axis::T => self.t,
            Axis::NegT => -self.t,
            Axis::B => self.b,
            Axis::NegB => -self.b,
            Axis::N => self.n,
            Axis::NegN => -self.n,
        }
    }

    /// Camera basis of a view: (right, up, forward), right-handed like the scene camera.
    pub fn basis(&self, view: &ViewLayout) -> (Vec3, Vec3, Vec3) {
        let forward = self.axis(view.forward);
        let up = self.axis(view.up);
        (forward.cross(up), up, forward)
    }

    /// World → Vulkan clip space of one view: square, reversed-Z, infinite far plane, NDC y down.
    pub fn view_proj(&self, view: &ViewLayout, near: f32) -> Mat4 {
        let (right, up, forward) = self.basis(view);
        projection(view.fov_deg.to_radians(), 1.0, near) * view_matrix(self.origin, right, up, forward)
    }

    /// The plane `dot(n, x − origin) = 0` as (n, −n·origin): positive above the horizon.
    pub fn horizon(&self) -> Vec4 {
        self.n.extend(-self.n.dot(self.origin))
    }

    /// World direction through the point `(ndc_x, ndc_y)` of a view (Vulkan NDC: y down, row 0 at −1).
    pub fn direction(&self, view: &ViewLayout, ndc_x: f32, ndc_y: f32) -> Vec3 {
        let (right, up, forward) = self.basis(view);
        let tan = (view.fov_deg.to_radians() * 0.5).tan();
        (forward + right * (ndc_x * tan) - up * (ndc_y * tan)).normalize()
    }

    pub fn to_world(&self, local: Vec3) -> Vec3 {
        self.t * local.x + self.b * local.y + self.n * local.z
    }
}

/// The turn of the sensor at pixel `(x, y)`: 2π times the R2 low-discrepancy sequence (Roberts 2018) over
/// the pixel grid, so that neighbouring pixels' turns are well spread and every turn is as likely.
pub fn pixel_turn(x: u32, y: u32) -> f32 {
    // The plastic number g: α = (1/g, 1/g²).
    const A1: f64 = 0.754_877_666_246_692_7;
    const A2: f64 = 0.569_840_290_998_053_2;
    let u = (0.5 + A1 * x as f64 + A2 * y as f64).fract();
    (std::f64::consts::TAU * u) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensors::SensorKind;
    use crate::sensors::layout::views;

    #[test]
    fn frame_is_orthonormal_right_handed_and_sign_of_zero_free() {
        for n in [Vec3::X, -Vec3::Y, Vec3::new(0.3, -0.4, 0.866).normalize(), Vec3::new(0.0, 0.0, -1.0)] {
            let f = SensorFrame::new(Vec3::ZERO, n, 0.0);
            assert!((f.t.cross(f.b) - f.n).length() < 1e-5, "{n}");
            assert!(f.t.dot(f.n).abs() < 1e-6 && f.b.dot(f.n).abs() < 1e-6);
        }
        let a = SensorFrame::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), 0.0);
        let b = SensorFrame::new(Vec3::ZERO, Vec3::new(1.0, 0.0, -0.0), 0.0);
        assert_eq!(a, b);
    }

    #[test]
    fn a_turned_frame_is_still_orthonormal_about_the_same_normal_and_turns_spread() {
        let f = SensorFrame::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.2, 0.9, -0.1).normalize(), 0.01);
        let g = f.turned(1.1);
        assert_eq!((g.n, g.origin), (f.n, f.origin));
        assert!((g.t.cross(g.b) - g.n).length() < 1e-5 && (g.t.dot(f.t) - 1.1f32.cos()).abs() < 1e-5);
        // Neighbouring pixels' turns differ; over a block they cover the circle evenly.
        let turns: Vec<f32> = (0..8).flat_map(|y| (0..8).map(move |x| pixel_turn(x, y))).collect();
        let mut counts = [0; 8];
        turns.iter().for_each(|t| counts[(t / std::f32::consts::TAU * 8.0) as usize % 8] += 1);
        assert!(counts.iter().all(|&c| (6..=10).contains(&c)), "turns of an 8 × 8 block by octant: {counts:?}");
        assert!((pixel_turn(3, 4) - pixel_turn(4, 4)).abs() > 0.1);
    }

    /// The projection sends the direction through an NDC point back to that NDC point.
    #[test]
    fn view_proj_and_direction_agree() {
        let frame = SensorFrame::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.2, 0.9, -0.1).normalize(), 0.01);
        for kind in [SensorKind::Hemicube, SensorKind::Frustum { fov_deg: 135.0 }] {
            for view in views(kind) {
                let m = frame.view_proj(&view, 0.001);
                for (x, y) in [(0.1, -0.3), (0.5, -0.25), (-0.9, 0.7), (0.0, 0.2)] {
                    let p = frame.origin + frame.direction(&view, x, y) * 7.0;
                    let clip = m * p.extend(1.0);
                    assert!((clip.x / clip.w - x).abs() < 1e-4 && (clip.y / clip.w - y).abs() < 1e-4, "{view:?}");
                    let above = frame.horizon().dot(p.extend(1.0)) > 0.0;
                    if view.clip_horizon {
                        // Rows of the upper half (ndc y < 0) see above the horizon for +up views, and the lower
                        // half does for −up views.
                        let up_is_n = frame.axis(view.up) == frame.n;
                        assert_eq!(above, (y < 0.0) == up_is_n, "{view:?} at {y}");
                    }
                }
            }
        }
    }
}
