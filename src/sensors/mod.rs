//! Sensors (paper §III-E): small cameras on visible points that render the scene around them.
//!
//! - [`frame`]: where a sensor sits and how it is oriented, and the view of each of its faces;
//! - [`layout`]: which layers of the sensor-map array a sensor's faces occupy;
//! - [`weights`]: the projected solid angle of every texel, shared by the GPU reduction and the tests;
//! - [`refine`]: where sensors go: the grid and its adaptive refinement.

pub mod frame;
pub mod layout;
pub mod refine;
pub mod weights;

use std::fmt;

use anyhow::{Result, bail, ensure};

/// What a sensor captures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SensorKind {
    /// The paper's sensor: one square perspective view of field of view `fov_deg` around the normal. Misses
    /// the directions outside the frustum (12.3 % of the cosine-weighted hemisphere at 135°).
    Frustum { fov_deg: f32 },
    /// A hemicube: the 90° front face and four half side faces; covers the whole hemisphere.
    Hemicube,
}

impl SensorKind {
    pub const DEFAULT_FOV_DEG: f32 = 135.0;

    /// `name` is "frustum" or "hemicube"; `fov_deg` applies to frustum sensors and must lie in (0, 180).
    pub fn parse(name: &str, fov_deg: f32) -> Result<Self> {
        // Checked for hemicubes too, which ignore it: a nonsense value is a mistake either way.
        ensure!(
            fov_deg.is_finite() && fov_deg > 0.0 && fov_deg < 180.0,
            "--fov must lie strictly between 0 and 180 degrees (a perspective view cannot see 180°), got {fov_deg}"
        );
        match name {
            "frustum" => Ok(Self::Frustum { fov_deg }),
            "hemicube" => Ok(Self::Hemicube),
            other => bail!("unknown sensor kind '{other}': expected 'frustum' or 'hemicube'"),
        }
    }

    /// Layers of the sensor-map array one sensor occupies.
    pub fn layers(self) -> u32 {
        layout::layers(self).len() as u32
    }

    /// Views (draws) one sensor needs.
    pub fn views(self) -> u32 {
        layout::views(self).len() as u32
    }

    /// Checks a sensor map size `rd` for this kind against the device's largest image side.
    pub fn check_size(self, rd: u32, max_image_side: u32) -> Result<()> {
        ensure!(rd >= 2, "--sensor-size must be at least 2 texels, got {rd}");
        ensure!(rd <= max_image_side, "--sensor-size {rd} exceeds this device's largest image side ({max_image_side})");
        if self == Self::Hemicube {
            ensure!(
                rd.is_multiple_of(2),
                "--sensor-size must be even for hemicube sensors (two half faces share a layer), got {rd}"
            );
        }
        Ok(())
    }
}

impl fmt::Display for SensorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Frustum { fov_deg } => write!(f, "frustum {fov_deg}°"),
            Self::Hemicube => write!(f, "hemicube"),
        }
    }
}
