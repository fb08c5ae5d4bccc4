//! Each parameter's names (its flag, its scene-file key), where a value came from, and the error that
//! names a bad value as the user wrote it.

use std::fmt;
use std::path::PathBuf;

/// A user-settable parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Param {
    Estimator,
    Sensor,
    Fov,
    Epsilon,
    Bounces,
    Background,
    SensorSize,
    Tile,
    Dradiance,
    FilterRadius,
    IndirectFilterRadius,
    CacheResolution,
    CacheSensorSize,
    Exposure,
    Samples,
    Aa,
}

impl Param {
    /// The command-line flag.
    pub fn flag(self) -> &'static str {
        match self {
            Self::Estimator => "--estimator",
            Self::Sensor => "--sensor",
            Self::Fov => "--fov",
            Self::Epsilon => "--epsilon",
            Self::Bounces => "--bounces",
            Self::Background => "--background",
            Self::SensorSize => "--sensor-size",
            Self::Tile => "--tile",
            Self::Dradiance => "--dradiance",
            Self::FilterRadius => "--filter-radius",
            Self::IndirectFilterRadius => "--indirect-filter-radius",
            Self::CacheResolution => "--cache-resolution",
            Self::CacheSensorSize => "--cache-sensor-size",
            Self::Exposure => "--exposure",
            Self::Samples => "--samples",
            Self::Aa => "--aa",
        }
    }

    /// The parameter as the user set it: the flag, or the scene file's `[render]` key.
    pub fn as_set(self, origin: &Origin) -> String {
        match origin {
            Origin::SceneFile(path) => format!("{}: [render] {}", path.display(), self.key()),
            _ => self.flag().to_owned(),
        }
    }

    /// The key in a scene file's `[render]` table.
    pub fn key(self) -> &'static str {
        match self {
            Self::Estimator => "estimator",
            Self::Sensor => "sensor",
            Self::Fov => "fov_deg",
            Self::Epsilon => "epsilon",
            Self::Bounces => "bounces",
            Self::Background => "background",
            Self::SensorSize => "sensor_size",
            Self::Tile => "tile",
            Self::Dradiance => "dradiance",
            Self::FilterRadius => "filter_radius",
            Self::IndirectFilterRadius => "indirect_filter_radius",
            Self::CacheResolution => "cache_resolution",
            Self::CacheSensorSize => "cache_sensor_size",
            Self::Exposure => "exposure",
            Self::Samples => "samples",
            Self::Aa => "aa",
        }
    }
}

/// Where a parameter's value came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    Flag,
    SceneFile(PathBuf),
    Default,
}

/// A parameter value out of its range, named as the user wrote it (once [`ParamError::origin`] is known).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub struct ParamError {
    pub param: Param,
    /// What is wrong, as a predicate: "must be a power of two (1, 2, 4, …), got 12".
    pub problem: String,
    /// `None` where the code that found the problem cannot know (e.g. a device limit checked by the
    /// renderer): [`RenderParams::attribute`] fills it in.
    pub origin: Option<Origin>,
}

impl ParamError {
    pub fn new(param: Param, problem: impl Into<String>) -> Self {
        Self { param, problem: problem.into(), origin: None }
    }
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let origin = self.origin.clone().unwrap_or(Origin::Flag);
        write!(f, "{} {}", self.param.as_set(&origin), self.problem)
    }
}
