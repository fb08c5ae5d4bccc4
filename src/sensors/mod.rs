//! Sensors (paper §III-E): small cameras on visible points that render the scene around them.
//!
//! - [`frame`]: where a sensor sits and how it is oriented, and the view of each of its faces;
//! - [`layout`]: which layers of the sensor-map array a sensor's faces occupy;
//! - [`weights`]: the projected solid angle of every texel, shared by the GPU reduction and the tests;
//! - [`refine`]: where sensors go: the grid and its adaptive refinement;
//! - [`hints`]: which points on the lights each pixel sees, so that the refinement misses no thin light;
//! - [`zoom`]: a sensor's zoom view of a light group, whose visibility it measures;
//! - [`views`]: a batch of sensors' views and what the reduction needs to know of them.

pub mod frame;
pub mod hints;
pub mod layout;
pub mod refine;
pub mod views;
pub mod weights;
pub mod zoom;

use std::fmt;

use clap::ValueEnum;
use serde::Deserialize;

/// The shape of a sensor, as a user chooses it (a frustum's field of view is a parameter of its own).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum SensorShape {
    /// The whole hemisphere: a front face and four half side faces (3 map layers).
    Hemicube,
    /// The paper's single square view of `--fov` degrees (1 layer; misses the hemisphere's rim).
    Frustum,
}

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
    /// A sensor of `shape`; `fov_deg` (in (0, 180), checked by the caller) applies to frustums only.
    pub fn new(shape: SensorShape, fov_deg: f32) -> Self {
        match shape {
            SensorShape::Hemicube => Self::Hemicube,
            SensorShape::Frustum => Self::Frustum { fov_deg },
        }
    }

    pub fn shape(self) -> SensorShape {
        match self {
            Self::Hemicube => SensorShape::Hemicube,
            Self::Frustum { .. } => SensorShape::Frustum,
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

    /// What is wrong with a sensor map size `rd` for this kind on a device whose largest image side is
    /// `max_image_side`, if anything (as a predicate: "must be even …").
    pub fn size_problem(self, rd: u32, max_image_side: u32) -> Option<String> {
        if rd < 2 {
            return Some(format!("must be at least 2 texels, got {rd}"));
        }
        if rd > max_image_side {
            return Some(format!("{rd} exceeds this device's largest image side ({max_image_side})"));
        }
        if self == Self::Hemicube && !rd.is_multiple_of(2) {
            return Some(format!("must be even for hemicube sensors (two half faces share a layer), got {rd}"));
        }
        None
    }
}

impl fmt::Display for SensorShape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Hemicube => "hemicube",
            Self::Frustum => "frustum",
        })
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
