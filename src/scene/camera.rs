//! The pinhole camera. Right-handed, y up: forward = normalize(target − eye), right = normalize(forward × up),
//! up' = right × forward; pixel row 0 is the top of the image. The G-buffer raster and the CPU ray caster
//! both derive their rays from this one type, so they sample the same pixel centres.

use anyhow::{Result, ensure};
use glam::{Mat4, Vec3, Vec4};

use super::Ray;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// Full vertical field of view, radians.
    pub vfov: f32,
}

impl Camera {
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, vfov_deg: f32) -> Result<Self> {
        ensure!(eye.is_finite() && target.is_finite() && up.is_finite(), "camera vectors must be finite");
        ensure!(vfov_deg > 0.0 && vfov_deg < 180.0, "camera vfov_deg must lie in (0, 180), got {vfov_deg}");
        let view = target - eye;
        ensure!(view.is_finite(), "camera eye and target are too far apart for 32-bit floats");
        let forward = direction(view).ok_or_else(|| anyhow::anyhow!("camera eye and target coincide"))?;
        ensure!(direction(up).is_some(), "camera up must not be zero");
        let right = direction(forward.cross(up))
            .ok_or_else(|| anyhow::anyhow!("camera up is parallel to the viewing direction"))?;
        Ok(Self { eye, forward, right, up: right.cross(forward), vfov: vfov_deg.to_radians() })
    }

    /// The ray through the continuous image point `(x, y)` in pixels (pixel centres at `i + 0.5`).
    pub fn ray(&self, x: f32, y: f32, width: u32, height: u32) -> Ray {
        let tan = (self.vfov * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let sx = (2.0 * x / width as f32 - 1.0) * tan * aspect;
        let sy = (1.0 - 2.0 * y / height as f32) * tan;
        Ray::new(self.eye, (self.forward + self.right * sx + self.up * sy).normalize())
    }

    /// Where the point `p` appears in an image of `width` × `height`, in continuous pixel coordinates (the
    /// inverse of [`Camera::ray`]); `None` behind the camera or at its eye.
    pub fn project(&self, p: Vec3, width: u32, height: u32) -> Option<glam::Vec2> {
        let d = p - self.eye;
        let z = d.dot(self.forward);
        if z <= 0.0 || !z.is_finite() {
            return None;
        }
        let tan = (self.vfov * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let (sx, sy) = (d.dot(self.right) / (z * tan * aspect), d.dot(self.up) / (z * tan));
        Some(glam::Vec2::new((sx + 1.0) * 0.5 * width as f32, (1.0 - sy) * 0.5 * height as f32))
    }

    /// World → Vulkan clip space matching [`Camera::ray`]: reversed-Z with an infinite far plane (depth 1 at
    /// `near`, → 0 at infinity; compare with GREATER), NDC y down so that row 0 is the top.
    pub fn view_proj(&self, width: u32, height: u32, near: f32) -> Mat4 {
        projection(self.vfov, width as f32 / height as f32, near)
            * view_matrix(self.eye, self.right, self.up, self.forward)
    }
}

/// The unit vector along `v`, or `None` for a zero vector. A finite vector whose length overflows f32
/// (components ≳ 1.8e19) is scaled down first and still has its direction; any other is normalised as is,
/// so that the camera of an ordinary scene is bit for bit what plain normalisation gives.
fn direction(v: Vec3) -> Option<Vec3> {
    let plain = v.normalize_or_zero();
    if plain != Vec3::ZERO {
        return Some(plain);
    }
    let largest = v.abs().max_element();
    (largest > 0.0 && largest.is_finite()).then(|| (v / largest).normalize())
}

/// World → view space for an eye with orthonormal `right`, `up`, `forward` (view space looks down −z).
pub fn view_matrix(eye: Vec3, right: Vec3, up: Vec3, forward: Vec3) -> Mat4 {
    let rotation = Mat4::from_cols(
        Vec4::new(right.x, up.x, -forward.x, 0.0),
        Vec4::new(right.y, up.y, -forward.y, 0.0),
        Vec4::new(right.z, up.z, -forward.z, 0.0),
        Vec4::W,
    );
    rotation * Mat4::from_translation(-eye)
}

/// View → Vulkan clip space: perspective of vertical field of view `vfov` (radians), reversed-Z with an
/// infinite far plane (depth = near / distance: 1 at the near plane, → 0 far away, compare GREATER; float
/// depth then keeps its precision at every distance), NDC y pointing down so that row 0 is the top.
pub fn projection(vfov: f32, aspect: f32, near: f32) -> Mat4 {
    let f = 1.0 / (vfov * 0.5).tan();
    Mat4::from_cols(
        Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, -f, 0.0, 0.0),
        Vec4::new(0.0, 0.0, 0.0, -1.0),
        Vec4::new(0.0, 0.0, near, 0.0),
    )
}
