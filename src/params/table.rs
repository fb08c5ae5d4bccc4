//! Every user-settable parameter, declared once: its flag, its scene-file key (`[render]`), its type,
//! default, range (the check) and help. The command line, the scene file, the checks and the resolved
//! values follow from this table (`declare.rs`); adding a parameter is one entry here plus its use.
//!
//! Each entry: `Name: Type { flag, key, value_name, default, [shown,] check, help }`. `shown` replaces the
//! default in `--help` where the default is not a value (a model, a rule). A check returns what is wrong
//! as a predicate ("must be …, got …").

use super::declare::{EstimatorDefault, Fallback, any};
use super::{Antialiasing, Bounces, EstimatorKind, Origin, ParamError, SensorShape};

pub const DEFAULT_ESTIMATOR: EstimatorKind = EstimatorKind::Exact;
/// ε of the paper's model when `--epsilon` is given without a value in mind (`metrics`, `bench`).
pub const DEFAULT_EPSILON: f32 = 0.1;
/// The filter's radius by estimator: the exact estimator leaves it little noise to remove (see
/// [`Param::FilterRadius`]); the paper's keeps the filter that hides its tiles.
pub const DEFAULT_FILTER_RADIUS: EstimatorDefault<u32> = EstimatorDefault { exact: 0, paper: 2 };
/// The widest filter: σ = 32 pixels blurs far beyond any sensor spacing, and each pixel reads (2r + 1)²
/// neighbours. (Measured on lavapipe: from r = 181, (2r + 1)² > 2¹⁷ iterations, the driver cut the loop
/// short and pixels were left without even their own sample: NaN.)
pub const MAX_FILTER_RADIUS: u32 = 64;
/// The most cells along an axis the cache's keys hold (`gi::grid::MAX_CELLS`, less the corner's offset).
pub const MAX_CACHE_RESOLUTION: u32 = 1022;

parameters! {
    /// How R is estimated from the maps: `exact` (the emitters in closed form, their visibility from the
    /// maps) or `paper` (the paper's eq. 3, what `metrics` reproduces).
    Estimator: EstimatorKind {
        flag: "--estimator",
        key: estimator,
        value_name: "KIND",
        default: Fallback::Value(DEFAULT_ESTIMATOR),
        check: any,
        help: "How R is read from the sensor maps",
    },
    /// `hemicube` (the whole hemisphere) or `frustum` (the paper's single view of `fov`).
    Sensor: SensorShape {
        flag: "--sensor",
        key: sensor,
        value_name: "SHAPE",
        default: Fallback::Value(SensorShape::Hemicube),
        check: any,
        help: "Sensor kind",
    },
    /// The frustum sensor's field of view in degrees, (0, 180); the paper's 90–150.
    Fov: f32 {
        flag: "--fov",
        key: fov_deg,
        value_name: "DEG",
        default: Fallback::Value(135.0),
        check: |fov| {
            require(fov.is_finite() && *fov > 0.0 && *fov < 180.0, || {
                format!("must lie strictly between 0 and 180 degrees (a perspective view cannot see 180°), got {fov}")
            })
        },
        help: "Field of view of frustum sensors, degrees, in (0, 180)",
    },
    /// The paper's model instead of global illumination: what a sensor sees on a non-emitter is `Kd·ε`.
    /// Radiance units, ≥ 0; 0 is direct light only; 0.05–0.3 typical for lights of `Ke` ≈ 10–20.
    Epsilon: f32 {
        flag: "--epsilon",
        key: epsilon,
        value_name: "E",
        default: Fallback::Value(DEFAULT_EPSILON),
        shown: "global illumination; metrics and bench: 0.1",
        check: finite_non_negative,
        help: "ε: the paper's model instead of global illumination: non-emitters seen by a sensor return Kd·ε \
               (≥ 0; 0 = direct light only)",
    },
    /// Global illumination's indirect bounces: a count (0 = direct light only) or `auto`, until converged.
    Bounces: Bounces {
        flag: "--bounces",
        key: bounces,
        value_name: "N|auto",
        default: Fallback::Value(Bounces::Converged),
        shown: "auto, unless --epsilon is given",
        check: any,
        help: "Global illumination: indirect bounces, N ≥ 0 (0 = direct light only; N is a path tracer's \
               maximum depth N + 2), or auto: until converged",
    },
    /// Radiance of rays that leave the scene, linear RGB, ≥ 0.
    Background: [f32; 3] {
        flag: "--background",
        key: background,
        value_name: "R,G,B",
        default: Fallback::Value([0.0; 3]),
        shown: "0,0,0; an OBJ mesh given to render or reference in which nothing emits: 1,1,1, a white sky",
        check: |rgb| {
            require(rgb.iter().all(|v| v.is_finite() && *v >= 0.0), || format!("must be finite and ≥ 0, got {rgb:?}"))
        },
        help: "Radiance of rays leaving the scene, as R,G,B",
    },
    /// rd: the sensor map's side in texels, 2 … the device's largest image side (even for hemicubes).
    /// Cost grows with rd². The exact estimator reads only visibility from its maps, through zoom views:
    /// 32² keeps every shipped and hard scene within 1 % of the oracle (docs/ACCURACY.md); 16–64 typical.
    /// The paper's estimator keeps the paper's 256 (128–256 typical).
    SensorSize: u32 {
        flag: "--sensor-size",
        key: sensor_size,
        value_name: "RD",
        default: Fallback::ByEstimator(EstimatorDefault { exact: 32, paper: 256 }),
        check: at_least_two_texels,
        help: "rd: sensor map side in texels (even for hemicubes; cost grows with rd²)",
    },
    /// dt: the adaptive refinement's initial grid step (paper §III-G), a power of two ≥ 1; 16 typical.
    Tile: u32 {
        flag: "--tile",
        key: tile,
        value_name: "DT",
        default: Fallback::Value(16),
        check: |tile| require(tile.is_power_of_two(), || format!("must be a power of two (1, 2, 4, …), got {tile}")),
        help: "dt: initial sensor grid step, a power of two",
    },
    /// The largest relative variation of R, and of each light group's visibility, between a quad's
    /// corners that is still interpolated; ≥ 0. 0 senses every pixel; 0.1–0.4 typical (0.2: every shipped
    /// and hard scene within 1 % of the oracle with the exact estimator; 0.1 halves the error in 1.4× the
    /// time); a huge value senses only the grid (and the light hints' boundaries).
    Dradiance: f32 {
        flag: "--dradiance",
        key: dradiance,
        value_name: "D",
        default: Fallback::Value(0.2),
        check: finite_non_negative,
        help: "Interpolate a quad when R varies by less than this between its corners (0 = sense every pixel)",
    },
    /// The id-constrained Gaussian filter's radius in pixels (paper §III-H), σ = radius / 2, 0 (off) …
    /// [`MAX_FILTER_RADIUS`]. It keeps to the centre pixel's surface and light mask; the exact estimator
    /// leaves it little noise to remove, so it is off there by default.
    FilterRadius: u32 {
        flag: "--filter-radius",
        key: filter_radius,
        value_name: "R",
        default: Fallback::ByEstimator(DEFAULT_FILTER_RADIUS),
        check: filter_radius,
        help: "Radius of the id-constrained Gaussian filter in pixels (0 = off)",
    },
    /// With global illumination and the exact estimator: the same filter's radius for R's indirect part
    /// alone, 0 … [`MAX_FILTER_RADIUS`]. The direct light keeps its sharp shadows; the indirect, smooth
    /// but aliased where it comes through a gap a texel wide (a door ajar), loses its pixel-to-pixel
    /// noise (docs/ACCURACY.md: the door ajar's error, the Cornell box's unchanged); 1 typical.
    IndirectFilterRadius: u32 {
        flag: "--indirect-filter-radius",
        key: indirect_filter_radius,
        value_name: "R",
        default: Fallback::Value(1),
        check: filter_radius,
        help: "Global illumination: the id-constrained filter's radius for the indirect light alone, in \
               pixels (0 = off; the direct light keeps its own, --filter-radius)",
    },
    /// Global illumination: the radiance cache's cells along the scene's longest side, 1 …
    /// [`MAX_CACHE_RESOLUTION`]; 8–32 typical. Its sensors (about 2 per cell of surface, so 4× for twice
    /// the resolution) are sensed once per bounce; the camera's sensors gather it, so it may be coarse
    /// (docs/ACCURACY.md: error against time).
    CacheResolution: u32 {
        flag: "--cache-resolution",
        key: cache_resolution,
        value_name: "N",
        default: Fallback::Value(16),
        check: |n| {
            let problem = || format!("must be 1 to {MAX_CACHE_RESOLUTION} cells, got {n}");
            require((1..=MAX_CACHE_RESOLUTION).contains(n), problem)
        },
        help: format!(
            "Global illumination: the radiance cache's cells along the scene's longest side, 1 to \
             {MAX_CACHE_RESOLUTION} (sensors per bounce grow with its square)"
        ),
    },
    /// rd of the radiance cache's sensors after its first bounce (which measures the direct light at
    /// `sensor_size`): they see only the smooth light surfaces reflect, which the camera's sensors then
    /// gather. 2 … the device's largest image side (even for hemicubes); 8–32 typical.
    CacheSensorSize: u32 {
        flag: "--cache-sensor-size",
        key: cache_sensor_size,
        value_name: "RD",
        default: Fallback::Value(16),
        check: at_least_two_texels,
        help: "Global illumination: rd of the radiance cache's sensors after its first bounce (even for \
               hemicubes)",
    },
    /// The PNG preview's exposure in stops (the EXR is never scaled); finite.
    Exposure: f32 {
        flag: "--exposure",
        key: exposure,
        value_name: "STOPS",
        default: Fallback::Value(0.0),
        shown: "the scene file's, else 0 unless more than 1 % of lit pixels would clip; a bare mesh: \
                automatic, its lit pixels' 99th percentile of luminance to white",
        check: |x| require(x.is_finite(), || format!("must be finite, got {x}")),
        help: "Exposure of the PNG preview, in stops. Tone mapping is linear: radiance × 2^exposure, clipped \
               to 1, sRGB-encoded (the EXR is never scaled)",
    },
    /// Whether a pixel is the mean over its square (`on`) or its centre alone (`off`, the paper's image).
    Aa: Antialiasing {
        flag: "--aa",
        key: aa,
        value_name: "MODE",
        default: Fallback::Value(Antialiasing::On),
        check: any,
        help: "A pixel is the mean over its square (`on`: sub-pixel samples where it is not uniform; the \
               reference integrates every pixel's square) or its centre alone (`off`: aliased edges, the \
               paper's image)",
    },
}

/// `Ok` where `ok`, else the problem `said`.
fn require(ok: bool, said: impl FnOnce() -> String) -> Result<(), String> {
    if ok { Ok(()) } else { Err(said()) }
}

fn finite_non_negative(x: &f32) -> Result<(), String> {
    require(x.is_finite() && *x >= 0.0, || format!("must be a finite number ≥ 0, got {x}"))
}

fn at_least_two_texels(rd: &u32) -> Result<(), String> {
    require(*rd >= 2, || format!("must be at least 2 texels, got {rd}"))
}

fn filter_radius(r: &u32) -> Result<(), String> {
    require(*r <= MAX_FILTER_RADIUS, || {
        format!("must be at most {MAX_FILTER_RADIUS} pixels (σ = radius / 2; the cost grows with radius²), got {r}")
    })
}
