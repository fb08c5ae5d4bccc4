//! The sun: a distant disc of emitting triangles, added to the mesh after its own triangles, so that
//! every part of the renderer treats it as the light it physically is. The exact estimator's closed form
//! gives its unoccluded irradiance (Lambert's formula on its facets), its zoom view its visibility, so its
//! penumbrae are those of a 0.53° disc; the oracle samples it as an area light.
//!
//! ```text
//!              ╱‾‾‾‾╲   SEGMENTS-gon of radius D·tan(α/2), facing the scene
//!             │  ●   │  at D = DISTANCE × the scene's diagonal, along `direction`
//!              ╲____╱   from the scene's centre
//!                ▲
//!                │ direction (unit, towards the sun)
//!           ┌────┴────┐
//!           │  scene  │
//! ```
//!
//! Over the scene, the sun's direction varies by diagonal / D (0.006°, a hundredth of its width) and its
//! irradiance by 2·diagonal / D (0.02 %).

use anyhow::{Result, ensure};
use glam::Vec3;

use super::Aabb;

/// How far the disc stands, in diagonals of the scene's bounds.
pub const DISTANCE: f32 = 1e4;
/// Sides of the polygon standing for the disc.
pub const SEGMENTS: usize = 32;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit vector from the scene towards the sun.
    pub direction: Vec3,
    /// Full angle the disc subtends, degrees (0.53 for the sun seen from the earth).
    pub angular_diameter_deg: f32,
    /// Irradiance on a surface facing the sun, unoccluded (linear RGB, W/m² or the scene's unit).
    pub irradiance: Vec3,
}

impl Sun {
    pub const DEFAULT_DIAMETER_DEG: f32 = 0.53;
    /// A white surface facing a sun of this irradiance has radiance 1 (E·ρ/π).
    pub const DEFAULT_IRRADIANCE: f32 = std::f32::consts::PI;
    /// The widest disc accepted: beyond it the light is no sun (and the disc's facets would show).
    pub const MAX_DIAMETER_DEG: f32 = 10.0;

    /// A sun towards `direction` (any length), checked: a direction, a diameter in (0, 10]°, an irradiance
    /// finite and not negative.
    pub fn new(direction: Vec3, angular_diameter_deg: f32, irradiance: Vec3) -> Result<Self> {
        let unit = direction.try_normalize();
        ensure!(unit.is_some(), "the sun's direction {direction} is not a direction (zero or not finite)");
        ensure!(
            angular_diameter_deg > 0.0 && angular_diameter_deg <= Self::MAX_DIAMETER_DEG,
            "the sun's angular diameter {angular_diameter_deg}° must be above 0 and at most {}°",
            Self::MAX_DIAMETER_DEG
        );
        ensure!(
            irradiance.is_finite() && irradiance.min_element() >= 0.0,
            "the sun's irradiance {irradiance} must be finite and not negative"
        );
        Ok(Self { direction: unit.unwrap(), angular_diameter_deg, irradiance })
    }

    /// The disc's facets for a scene of `bounds`, counter-clockwise seen from the scene (their fronts
    /// emit towards it), and their radiance: that which gives the stated irradiance through the polygon's
    /// projected solid angle `A / (D² + A/π)` (exact for a round disc of the polygon's area `A` seen along
    /// its axis; the polygon has the round disc's area).
    pub fn facets(&self, bounds: &Aabb) -> (Vec<[Vec3; 3]>, Vec3) {
        let distance = DISTANCE * bounds.diagonal().max(f32::MIN_POSITIVE);
        let centre = bounds.center() + self.direction * distance;
        let step = std::f32::consts::TAU / SEGMENTS as f32;
        // The polygon as large as the round disc: its corners a third of a percent further out.
        let round = distance * (0.5 * self.angular_diameter_deg.to_radians()).tan();
        let radius = round * (std::f32::consts::PI / (0.5 * SEGMENTS as f32 * step.sin())).sqrt();
        let (a, b) = self.direction.any_orthonormal_pair();
        let rim = |k: usize| centre + (a * (k as f32 * step).cos() + b * (k as f32 * step).sin()) * radius;
        // Seen from the scene (looking along −direction … +direction), a → b turns clockwise: reversed.
        let triangles: Vec<[Vec3; 3]> = (0..SEGMENTS).map(|k| [centre, rim(k + 1), rim(k)]).collect();
        let area = 0.5 * SEGMENTS as f32 * radius * radius * step.sin();
        let projected = area / (distance * distance + area / std::f32::consts::PI);
        (triangles, self.irradiance / projected)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_disc_faces_the_scene_and_subtends_its_diameter() {
        let bounds = Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        let sun = Sun::new(Vec3::new(0.3, 1.0, 0.2), 0.53, Vec3::splat(1000.0)).unwrap();
        let (triangles, radiance) = sun.facets(&bounds);
        assert_eq!(triangles.len(), SEGMENTS);
        for t in &triangles {
            let normal = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            assert!(normal.dot(-sun.direction) > 0.9999, "the front faces the scene");
        }
        // From the centre, the corners are 0.265° off the sun's direction (a third of a percent more).
        let rim = triangles[0][1].normalize();
        assert!((rim.dot(sun.direction).acos().to_degrees() - 0.265).abs() < 2e-3);
        // L · Ω ≈ E: the disc's solid angle is π sin²(α/2).
        let omega = std::f32::consts::PI * (0.265f32.to_radians()).sin().powi(2);
        assert!((radiance.x * omega / 1000.0 - 1.0).abs() < 2e-3, "{}", radiance.x * omega);
    }

    #[test]
    fn a_bad_sun_is_refused_with_what_is_wrong() {
        assert!(format!("{}", Sun::new(Vec3::ZERO, 0.53, Vec3::ONE).unwrap_err()).contains("not a direction"));
        assert!(format!("{}", Sun::new(Vec3::Y, 0.0, Vec3::ONE).unwrap_err()).contains("angular diameter"));
        assert!(format!("{}", Sun::new(Vec3::Y, 0.5, -Vec3::ONE).unwrap_err()).contains("irradiance"));
    }
}
