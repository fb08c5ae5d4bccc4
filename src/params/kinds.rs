//! The typed choices among the parameters: the estimator, antialiasing, and the model of indirect light
//! (the paper's `Kd·ε`, or bounces of global illumination).

use std::fmt;

use serde::Deserialize;

use super::DEFAULT_EPSILON;

/// How R is estimated from a sensor's maps (docs/DESIGN.md §2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EstimatorKind {
    /// The emitters' unoccluded light in closed form, only their visibility read from the maps (zoom views
    /// per light group); the rest as rasterised.
    #[default]
    Exact,
    /// The paper's (its eq. 3): every texel's Ck summed, emitters included; what `metrics` reproduces.
    Paper,
}

impl fmt::Display for EstimatorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Exact => "exact",
            Self::Paper => "paper",
        })
    }
}

/// What a pixel's value is the mean over (docs/DESIGN.md §11).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Antialiasing {
    /// The pixel's square, as a camera's sensor and every reference renderer (a box filter): where a pixel
    /// is not uniform (an edge, a crease, a shadow's edge, a sliver thinner than a pixel) it takes sub-pixel
    /// samples; the oracle integrates every pixel over its square.
    #[default]
    On,
    /// One sample at the pixel's centre: the paper's image (what `metrics` reproduces), aliased edges.
    Off,
}

impl fmt::Display for Antialiasing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::On => "on",
            Self::Off => "off",
        })
    }
}

/// How many times light is reflected between surfaces before it reaches a visible point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bounces {
    /// Exactly this many indirect bounces; 0 is direct light only. N indirect bounces are a path tracer's
    /// maximum depth N + 2 (Mitsuba's convention: depth 1 sees the emitters, depth 2 adds direct light).
    Fixed(u32),
    /// Until what a bounce adds is negligible: the renderer stops when the cache changes by less than its
    /// tolerance and extrapolates the rest of the series; the oracle traces paths of any length (Russian
    /// roulette ends them).
    Converged,
}

impl std::str::FromStr for Bounces {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "auto" => Ok(Self::Converged),
            n => n
                .parse()
                .map(Self::Fixed)
                .map_err(|_| format!("expected a count of bounces (0, 1, 2, …) or 'auto', got '{s}'")),
        }
    }
}

impl fmt::Display for Bounces {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Fixed(n) => write!(f, "{n}"),
            Self::Converged => f.write_str("auto"),
        }
    }
}

impl<'de> Deserialize<'de> for Bounces {
    /// `bounces = 3` or `bounces = "auto"` in a scene file's `[render]` table.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Count(u32),
            Word(String),
        }
        match Raw::deserialize(d)? {
            Raw::Count(n) => Ok(Self::Fixed(n)),
            Raw::Word(w) => w.parse().map_err(serde::de::Error::custom),
        }
    }
}

/// What a sensor sees on a surface that does not emit towards it (docs/DESIGN.md §1): the paper's constant,
/// or the light that surface really reflects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Indirect {
    /// The paper's model (its eq. 2): `Kd·ε`, a constant standing in for the light a surface reflects.
    /// Radiance units, ≥ 0; 0 is direct light only; typical 0.05–0.3 for lights of `Ke` ≈ 10–20.
    Epsilon(f32),
    /// Global illumination: the outgoing radiance `Le + Kd·R` of the surface seen, through this many bounces.
    Bounces(Bounces),
}

impl Indirect {
    /// ε as the sensor maps use it: the paper's constant, 0 with global illumination (whose maps read the
    /// radiance cache instead).
    pub fn epsilon(self) -> f32 {
        match self {
            Self::Epsilon(e) => e,
            Self::Bounces(_) => 0.0,
        }
    }

    /// ε for what measures the paper's sensors (`metrics`, `bench`): this model's, or [`DEFAULT_EPSILON`]
    /// where global illumination was asked for.
    pub fn paper_epsilon(self) -> f32 {
        match self {
            Self::Epsilon(e) => e,
            Self::Bounces(_) => DEFAULT_EPSILON,
        }
    }

    /// The indirect bounces to compute: none with the paper's model (its ε is no bounce).
    pub fn bounces(self) -> Option<Bounces> {
        match self {
            Self::Epsilon(_) | Self::Bounces(Bounces::Fixed(0)) => None,
            Self::Bounces(b) => Some(b),
        }
    }
}

impl fmt::Display for Indirect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Epsilon(e) => write!(f, "the paper's ε {e}"),
            Self::Bounces(Bounces::Fixed(0)) => f.write_str("direct light only"),
            Self::Bounces(Bounces::Fixed(1)) => f.write_str("global illumination, 1 indirect bounce"),
            Self::Bounces(Bounces::Fixed(n)) => write!(f, "global illumination, {n} indirect bounces"),
            Self::Bounces(Bounces::Converged) => f.write_str("global illumination until converged"),
        }
    }
}
