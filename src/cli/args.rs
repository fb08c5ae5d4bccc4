//! Flags shared by several sub-commands, and how they become [`Overrides`]. Defaults shown in `--help` are
//! taken from the constants in `params`, so they cannot drift from what the program does.

use std::path::PathBuf;

use anyhow::{Context as _, Result, ensure};
use clap::Args;
use glam::Vec3;
use sensorlight::params::{
    Bounces, DEFAULT_CACHE_RESOLUTION, DEFAULT_CACHE_SENSOR_SIZE, DEFAULT_DRADIANCE, DEFAULT_EPSILON,
    DEFAULT_ESTIMATOR, DEFAULT_EXPOSURE, DEFAULT_FILTER_RADIUS, DEFAULT_FOV_DEG, DEFAULT_INDIRECT_FILTER_RADIUS,
    DEFAULT_SENSOR, DEFAULT_SENSOR_SIZE, DEFAULT_TILE, EstimatorKind, MAX_CACHE_RESOLUTION, Overrides, SensorShape,
};
use sensorlight::renderer::DEFAULT_IN_FLIGHT;
use sensorlight::scene::{ImageSize, Scene, SkyMap, Sun};
use sensorlight::strategy::StrategyRequest;

/// What a sensor sees: shared by `render`, `reference` and `bench`.
#[derive(Args, Clone, Debug, Default)]
pub struct EstimatorFlags {
    #[arg(
        long,
        value_enum,
        help = format!("Sensor kind [default: {DEFAULT_SENSOR}]")
    )]
    pub sensor: Option<SensorShape>,
    #[arg(
        long = "fov",
        allow_negative_numbers = true,
        help = format!("Field of view of frustum sensors, degrees, in (0, 180) [default: {DEFAULT_FOV_DEG}]")
    )]
    pub fov_deg: Option<f32>,
    #[arg(
        long,
        allow_negative_numbers = true,
        help = format!(
            "ε: the paper's model instead of global illumination: non-emitters seen by a sensor return Kd·ε \
             (≥ 0; 0 = direct light only) [default: global illumination; metrics and bench: {DEFAULT_EPSILON}]"
        )
    )]
    pub epsilon: Option<f32>,
    /// Radiance of rays leaving the scene, as R,G,B [default: 0,0,0; an OBJ mesh given to render or reference in
    /// which nothing emits: 1,1,1, a white sky]
    #[arg(long, value_parser = parse_rgb, allow_negative_numbers = true)]
    pub background: Option<[f32; 3]>,
}

/// The light between surfaces: shared by `render` and `reference` (the paper's measurements keep its ε).
#[derive(Args, Clone, Debug, Default)]
pub struct BounceFlags {
    /// Global illumination: indirect bounces, N ≥ 0 (0 = direct light only; N is a path tracer's maximum
    /// depth N + 2), or auto: until converged [default: auto, unless --epsilon is given]
    #[arg(long, value_name = "N|auto", allow_negative_numbers = true)]
    pub bounces: Option<Bounces>,
}

impl BounceFlags {
    /// `base` with these flags set.
    pub fn overrides(&self, base: Overrides) -> Overrides {
        Overrides { bounces: self.bounces, ..base }
    }
}

/// Adaptive refinement and filtering (paper §III-G, §III-H): shared by `render` and `metrics`.
#[derive(Args, Clone, Debug, Default)]
pub struct RefinementFlags {
    #[arg(long, value_parser = whole, allow_negative_numbers = true, help = format!("dt: initial sensor grid step, a power of two [default: {DEFAULT_TILE}]"))]
    pub tile: Option<u32>,
    #[arg(
        long,
        allow_negative_numbers = true,
        help = format!(
            "Interpolate a quad when R varies by less than this between its corners (0 = sense every pixel) \
             [default: {DEFAULT_DRADIANCE}]"
        )
    )]
    pub dradiance: Option<f32>,
    #[arg(value_parser = whole, allow_negative_numbers = true,
        long,
        help = format!(
            "Radius of the id-constrained Gaussian filter in pixels (0 = off) [default: {DEFAULT_FILTER_RADIUS}]"
        )
    )]
    pub filter_radius: Option<u32>,
}

/// `--estimator`'s help, with the default of the command that shows it.
pub fn estimator_help(default: EstimatorKind) -> String {
    format!("How R is read from the sensor maps [default: {default}]")
}

/// The sensor map size: shared by `render` and `metrics`.
pub fn sensor_size_help() -> String {
    format!("rd: sensor map side in texels (even for hemicubes; cost grows with rd²) [default: {DEFAULT_SENSOR_SIZE}]")
}

/// The sun and the sky map, on top of (or in place of) the scene's `[sun]` and `[sky]`: shared by `render`
/// and `reference`.
#[derive(Args, Clone, Debug, Default)]
pub struct LightFlags {
    /// Light the scene with a sun in this direction (x,y,z towards the sun; a 0.53° disc, `scene::sun`)
    /// [default: the scene's [sun], if any]
    #[arg(long, value_parser = parse_xyz, allow_hyphen_values = true, value_name = "X,Y,Z")]
    pub sun: Option<[f32; 3]>,
    /// The sun's irradiance on a surface facing it, R,G,B (a white surface facing a sun of π has radiance 1)
    /// [default: the scene's, else π]
    #[arg(long, value_parser = parse_rgb, value_name = "R,G,B")]
    pub sun_irradiance: Option<[f32; 3]>,
    /// The sun's angular diameter in degrees [default: the scene's, else 0.53]
    #[arg(long, value_name = "DEG")]
    pub sun_diameter: Option<f32>,
    /// Light the scene with this sky: an equirectangular environment map (OpenEXR or Radiance HDR, linear
    /// radiance, +y up), seen by every ray that leaves the scene [default: the scene's [sky], if any]
    #[arg(long, value_name = "FILE")]
    pub sky: Option<PathBuf>,
    /// Multiply the sky map by this [default: the scene's, else 1]
    #[arg(long, value_name = "K")]
    pub sky_strength: Option<f32>,
    /// Turn the sky map about +y by this many degrees, counter-clockwise seen from above [default: the
    /// scene's, else 0]
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub sky_rotation: Option<f32>,
}

impl LightFlags {
    /// The sun these flags ask for over the scene's `current` one: `None` where they ask for nothing.
    pub fn sun(&self, current: Option<&Sun>) -> Result<Option<Sun>> {
        if self.sun.is_none() && self.sun_irradiance.is_none() && self.sun_diameter.is_none() {
            return Ok(None);
        }
        let Some(direction) = self.sun.map(Vec3::from).or(current.map(|s| s.direction)) else {
            anyhow::bail!("--sun-irradiance and --sun-diameter need a sun: give its direction with --sun X,Y,Z");
        };
        let irradiance = self.sun_irradiance.map(Vec3::from).or(current.map(|s| s.irradiance));
        let diameter = self.sun_diameter.or(current.map(|s| s.angular_diameter_deg));
        Sun::new(
            direction,
            diameter.unwrap_or(Sun::DEFAULT_DIAMETER_DEG),
            irradiance.unwrap_or(Vec3::splat(Sun::DEFAULT_IRRADIANCE)),
        )
        .map(Some)
        .map_err(|e| anyhow::anyhow!("--sun: {e}"))
    }

    /// Lights `scene` with the sun and the sky map these flags ask for, in place of its own.
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        if let Some(sun) = self.sun(scene.sun.as_ref())? {
            scene.set_sun(sun);
        }
        let changes = self.sky_strength.is_some() || self.sky_rotation.is_some();
        let path = match (&self.sky, &scene.sky) {
            (Some(path), _) => path.clone(),
            (None, Some(current)) if changes => PathBuf::from(&current.name),
            (None, None) if changes => {
                anyhow::bail!("--sky-strength and --sky-rotation need a sky map: give one with --sky FILE")
            }
            (None, _) => return Ok(()),
        };
        let strength = self.sky_strength.or(scene.sky.as_ref().map(|s| s.strength)).unwrap_or(1.0);
        let rotation = self.sky_rotation.or(scene.sky.as_ref().map(|s| s.rotation_deg)).unwrap_or(0.0);
        let sky = SkyMap::load(&path, strength).and_then(|sky| sky.turned(rotation));
        scene.set_sky(sky.map_err(|e| anyhow::anyhow!("--sky: {e:#}"))?).context("--sky")?;
        Ok(())
    }
}

/// What decides the image: the estimator, the bounces, the size and exposure, the lights, the refinement and
/// the radiance cache. Shared by `render` and `view`, so both show the same image for the same flags.
#[derive(Args)]
pub struct LookFlags {
    #[command(flatten)]
    pub estimator: EstimatorFlags,
    #[command(flatten)]
    pub bounces: BounceFlags,
    #[command(flatten)]
    pub image: ImageFlags,
    #[command(flatten)]
    pub lights: LightFlags,
    #[arg(long = "estimator", value_enum, help = estimator_help(DEFAULT_ESTIMATOR))]
    pub estimator_kind: Option<EstimatorKind>,
    #[arg(long, value_parser = whole, allow_negative_numbers = true, help = sensor_size_help())]
    pub sensor_size: Option<u32>,
    #[command(flatten)]
    pub refinement: RefinementFlags,
    #[arg(long, value_parser = whole, allow_negative_numbers = true, help = format!(
        "Global illumination: the radiance cache's cells along the scene's longest side, 1 to \
         {MAX_CACHE_RESOLUTION} (sensors per bounce grow with its square) [default: {DEFAULT_CACHE_RESOLUTION}]"
    ))]
    pub cache_resolution: Option<u32>,
    #[arg(long, value_parser = whole, allow_negative_numbers = true, help = format!(
        "Global illumination: the id-constrained filter's radius for the indirect light alone, in pixels \
         (0 = off; the direct light keeps its own, --filter-radius) [default: {DEFAULT_INDIRECT_FILTER_RADIUS}]"
    ))]
    pub indirect_filter_radius: Option<u32>,
    #[arg(long, value_parser = whole, allow_negative_numbers = true, help = format!(
        "Global illumination: rd of the radiance cache's sensors after its first bounce (even for hemicubes) \
         [default: {DEFAULT_CACHE_SENSOR_SIZE}]"
    ))]
    pub cache_sensor_size: Option<u32>,
}

impl LookFlags {
    /// These flags as overrides of a scene file's `[render]` table.
    pub fn overrides(&self) -> Overrides {
        self.refinement.overrides(self.bounces.overrides(Overrides {
            estimator: self.estimator_kind,
            sensor_size: self.sensor_size,
            cache_resolution: self.cache_resolution,
            indirect_filter_radius: self.indirect_filter_radius,
            cache_sensor_size: self.cache_sensor_size,
            exposure: self.image.exposure,
            aa: self.image.aa,
            ..self.estimator.overrides()
        }))
    }
}

/// How the renderer runs on the device: which device, the batching strategy, batches in flight and their
/// memory. Shared by `render` and `view`.
#[derive(Args)]
pub struct EngineFlags {
    /// Memory for one batch of sensor maps, MiB [default: the batches in flight share 1/8 of the device's
    /// local memory]
    #[arg(long)]
    pub memory_budget: Option<u64>,
    /// Batches in flight: while the device renders one, the host prepares the next (each has its own maps)
    #[arg(long, default_value_t = DEFAULT_IN_FLIGHT, value_parser = clap::value_parser!(u32).range(1..=8))]
    pub in_flight: u32,
    /// How sensors are batched: auto (the fastest that passes its self-check here) or a strategy, used only
    /// if it passes its self-check
    #[arg(long, value_enum, default_value_t = StrategyRequest::Auto)]
    pub strategy: StrategyRequest,
    /// Device index from `sensorlight devices` [default: the best available]
    #[arg(long)]
    pub device: Option<usize>,
}

/// Output size and preview: shared by `render` and `reference`.
#[derive(Args, Clone, Debug, Default)]
pub struct ImageFlags {
    /// Image width in pixels [default: the scene's]
    #[arg(long, value_parser = whole, allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Image height in pixels [default: the scene's]
    #[arg(long, value_parser = whole, allow_negative_numbers = true)]
    pub height: Option<u32>,
    #[arg(
        long,
        allow_negative_numbers = true,
        help = format!(
            "Exposure of the PNG preview, in stops. Tone mapping is linear: radiance × 2^exposure, clipped to 1, \
             sRGB-encoded (the EXR is never scaled) [default: the scene file's, else {DEFAULT_EXPOSURE} unless more \
             than 1 % of lit pixels would clip; a bare mesh: automatic, its lit pixels' 99th percentile of \
             luminance to white]"
        )
    )]
    pub exposure: Option<f32>,
    /// Write a tone-mapped sRGB PNG beside the EXR (the default)
    #[arg(long, overrides_with = "no_png")]
    pub png: bool,
    /// Do not write the PNG
    #[arg(long, overrides_with = "png")]
    pub no_png: bool,
    /// A pixel is the mean over its square (`on`: sub-pixel samples where it is not uniform; the reference
    /// integrates every pixel's square) or its centre alone (`off`: aliased edges, the paper's image)
    /// [default: on]
    #[arg(long, value_enum)]
    pub aa: Option<sensorlight::params::Antialiasing>,
}

impl EstimatorFlags {
    pub fn overrides(&self) -> Overrides {
        Overrides {
            sensor: self.sensor,
            fov_deg: self.fov_deg,
            epsilon: self.epsilon,
            background: self.background,
            ..Default::default()
        }
    }
}

impl RefinementFlags {
    /// `base` with these flags set.
    pub fn overrides(&self, base: Overrides) -> Overrides {
        Overrides { tile: self.tile, dradiance: self.dradiance, filter_radius: self.filter_radius, ..base }
    }
}

impl ImageFlags {
    pub fn write_png(&self) -> bool {
        !self.no_png
    }

    /// The output size: these flags, else the scene's `[image]`.
    pub fn size(&self, scene: &Scene) -> Result<ImageSize> {
        let size = ImageSize {
            width: self.width.unwrap_or(scene.image.width),
            height: self.height.unwrap_or(scene.image.height),
        };
        ensure!(size.width >= 1 && size.height >= 1, "--width and --height must be at least 1");
        Ok(size)
    }
}

fn parse_xyz(s: &str) -> Result<[f32; 3], String> {
    let values: Result<Vec<f32>, _> = s.split(',').map(|p| p.trim().parse::<f32>()).collect();
    match values {
        Ok(v) if v.len() == 3 => Ok([v[0], v[1], v[2]]),
        _ => Err(format!("expected X,Y,Z, got '{s}'")),
    }
}

fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let values: Result<Vec<f32>, _> = parts.iter().map(|p| p.trim().parse::<f32>()).collect();
    match values {
        Ok(v) if v.len() == 3 => Ok([v[0], v[1], v[2]]),
        Ok(v) if v.len() == 1 => Ok([v[0]; 3]),
        _ => Err(format!("expected R,G,B (or one value for grey), got '{s}'")),
    }
}

/// A whole number for a count or size flag: a negative one is said as such, not as clap's tip to pass it
/// after `--`.
fn whole(text: &str) -> Result<u32, String> {
    match text.trim().parse::<i64>() {
        Ok(n) if n < 0 => Err(format!("{n} is negative; a whole number of 0 or more is expected")),
        Ok(n) => u32::try_from(n).map_err(|_| format!("{n} is too large (at most {})", u32::MAX)),
        Err(_) => Err(format!("'{text}' is not a whole number")),
    }
}
