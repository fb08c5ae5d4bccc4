//! The viewer's camera: an eye turning about a target point, the way 3D tools move one with the mouse.
//! Orbit turns the eye about the target (about the world's up, then the camera's right), pan moves both in
//! the image plane, dolly moves the eye along the line of sight. Each move makes a [`Camera`] by
//! [`Camera::look_at`], so a scene file holding [`Orbit::eye`], [`Orbit::target`], [`Orbit::up`] and
//! [`Orbit::vfov_deg`] renders exactly what the viewer showed.

use anyhow::Result;
use glam::{Quat, Vec3};

use crate::scene::{Aabb, Camera};

/// How close the line of sight may come to the world's up, degrees: beyond it `look_at` has no right.
const POLE_MARGIN_DEG: f32 = 1.0;

/// The camera the viewer moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub eye: Vec3,
    pub target: Vec3,
    /// The world's up: kept from the scene's camera, so orbiting never rolls the horizon.
    pub up: Vec3,
    /// Full vertical field of view.
    pub vfov_deg: f32,
    /// The least distance from eye to target: a dolly stops there.
    min_distance: f32,
}

impl Orbit {
    /// `camera` turning about the point of its line of sight level with the centre of `bounds` (at least
    /// 5 % of the scene's size ahead of the eye).
    pub fn new(camera: &Camera, bounds: &Aabb) -> Self {
        let size = bounds.diagonal().max(f32::MIN_POSITIVE);
        let distance = (bounds.center() - camera.eye).dot(camera.forward).max(0.05 * size);
        Self {
            eye: camera.eye,
            target: camera.eye + camera.forward * distance,
            up: camera.up,
            vfov_deg: camera.vfov.to_degrees(),
            min_distance: 1e-3 * size,
        }
    }

    pub fn distance(&self) -> f32 {
        (self.target - self.eye).length()
    }

    /// The camera this orbit describes.
    pub fn camera(&self) -> Result<Camera> {
        Camera::look_at(self.eye, self.target, self.up, self.vfov_deg)
    }

    /// Turns the eye about the target: `yaw_deg` about the world's up (right-handed: positive moves the eye
    /// to its left seen from above when up is +y), then `pitch_deg` about the camera's right (positive
    /// raises the eye), stopping short of looking straight along up.
    pub fn orbit(&mut self, yaw_deg: f32, pitch_deg: f32) {
        let up = self.up.normalize();
        let mut offset = Quat::from_axis_angle(up, yaw_deg.to_radians()) * (self.eye - self.target);
        let right = (-offset).cross(up).normalize_or_zero();
        if right != Vec3::ZERO {
            // Angle between the offset and up, kept within (margin, 180° − margin).
            let now = offset.angle_between(up).to_degrees();
            let pitch = (now - pitch_deg).clamp(POLE_MARGIN_DEG, 180.0 - POLE_MARGIN_DEG) - now;
            offset = Quat::from_axis_angle(right, pitch.to_radians()) * offset;
        }
        self.eye = self.target + offset;
    }

    /// Moves eye and target by `x` and `y` view heights at the target's distance (positive: right, up).
    pub fn pan(&mut self, x: f32, y: f32) {
        let Ok(camera) = self.camera() else { return };
        let height = 2.0 * self.distance() * (0.5 * self.vfov_deg.to_radians()).tan();
        let shift = (camera.right * x + camera.up * y) * height;
        self.eye += shift;
        self.target += shift;
    }

    /// Multiplies the eye's distance to the target by `factor` (< 1 closer), never nearer than the least.
    pub fn dolly(&mut self, factor: f32) {
        if !(factor.is_finite() && factor > 0.0) {
            return;
        }
        let distance = (self.distance() * factor).max(self.min_distance);
        self.eye = self.target + (self.eye - self.target).normalize() * distance;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell() -> (Camera, Aabb) {
        let camera = Camera::look_at(Vec3::new(278.0, 273.0, -800.0), Vec3::new(278.0, 273.0, 0.0), Vec3::Y, 39.3);
        (camera.unwrap(), Aabb { min: Vec3::ZERO, max: Vec3::new(556.0, 548.8, 559.2) })
    }

    #[test]
    fn an_unmoved_orbit_is_the_scenes_camera() {
        let (camera, bounds) = cornell();
        let orbit = Orbit::new(&camera, &bounds);
        assert!((orbit.target - Vec3::new(278.0, 273.0, 279.6)).length() < 1e-3, "{}", orbit.target);
        let again = orbit.camera().unwrap();
        for (a, b) in [(again.forward, camera.forward), (again.right, camera.right), (again.up, camera.up)] {
            assert!((a - b).length() < 1e-6, "{a} vs {b}");
        }
        assert!((again.vfov - camera.vfov).abs() < 1e-6);
    }

    #[test]
    fn orbiting_keeps_the_target_and_distance_and_turns_by_the_angle() {
        let (camera, bounds) = cornell();
        let mut orbit = Orbit::new(&camera, &bounds);
        let (start, d) = (orbit, orbit.distance());
        orbit.orbit(90.0, 0.0);
        assert_eq!(orbit.target, start.target);
        assert!((orbit.distance() - d).abs() < 1e-3 * d);
        // A quarter turn about +y takes the eye from −z of the target to −x (right-handed).
        let dir = (orbit.eye - orbit.target).normalize();
        assert!((dir - Vec3::NEG_X).length() < 1e-5, "{dir}");
        orbit.orbit(-90.0, 0.0);
        assert!((orbit.eye - start.eye).length() < 1e-3, "{} vs {}", orbit.eye, start.eye);
        // Pitch raises the eye and stops short of the pole.
        orbit.orbit(0.0, 30.0);
        let raised = (orbit.eye - orbit.target).normalize();
        assert!((raised.y - 30f32.to_radians().sin()).abs() < 1e-5, "{raised}");
        orbit.orbit(0.0, 200.0);
        let top = (orbit.eye - orbit.target).normalize().angle_between(Vec3::Y).to_degrees();
        assert!((top - POLE_MARGIN_DEG).abs() < 1e-2, "{top}");
        assert!(orbit.camera().is_ok(), "still a camera at the pole's margin");
    }

    #[test]
    fn pan_moves_eye_and_target_together_and_dolly_scales_the_distance() {
        let (camera, bounds) = cornell();
        let mut orbit = Orbit::new(&camera, &bounds);
        let start = orbit;
        orbit.pan(0.5, 0.0);
        let height = 2.0 * start.distance() * (0.5 * start.vfov_deg.to_radians()).tan();
        assert!((orbit.eye - start.eye - camera.right * 0.5 * height).length() < 1e-2);
        assert!(((orbit.target - orbit.eye) - (start.target - start.eye)).length() < 1e-3);
        orbit.dolly(0.5);
        assert!((orbit.distance() - 0.5 * start.distance()).abs() < 1e-2);
        orbit.dolly(0.0);
        orbit.dolly(f32::NAN);
        assert!((orbit.distance() - 0.5 * start.distance()).abs() < 1e-2, "bad factors are ignored");
        orbit.dolly(1e-9);
        assert!(orbit.distance() >= 1e-3 * bounds.diagonal() * 0.999, "a dolly stops short of the target");
    }
}
