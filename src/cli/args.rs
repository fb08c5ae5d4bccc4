//! Flags shared by several sub-commands. The parameters' flags come from their table (`params/table.rs`),
//! so `--help`, the scene file and what the program does cannot drift apart.

use std::path::PathBuf;

use anyhow::{Context as _, Result, ensure};
use clap::{Args, ValueEnum as _};
use glam::Vec3;
use sensorlight::params::flags::{FlagSet, FlagValue as _, ParamFlags, parse_rgb, whole};
use sensorlight::params::{Overrides, Param};
use sensorlight::renderer::DEFAULT_IN_FLIGHT;
use sensorlight::scene::{ImageSize, Scene, SkyMap, Sun};
use sensorlight::strategy::StrategyRequest;

/// Every parameter of the table: what `render` and `view` take.
pub enum Look {}

impl FlagSet for Look {
    const PARAMS: &'static [Param] = Param::ALL;
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

/// What decides the image: every parameter, the size and the lights. Shared by `render` and `view`, so
/// both show the same image for the same flags.
#[derive(Args)]
pub struct LookFlags {
    #[command(flatten)]
    pub params: ParamFlags<Look>,
    #[command(flatten)]
    pub image: ImageFlags,
    #[command(flatten)]
    pub lights: LightFlags,
}

impl LookFlags {
    /// These flags as overrides of a scene file's `[render]` table.
    pub fn overrides(&self) -> Overrides {
        self.params.values.clone()
    }

    /// The flags given, as a command line takes them: to pass them on to the processes of a job (paths made
    /// absolute, for a job that runs elsewhere).
    pub fn to_args(&self) -> Result<Vec<String>> {
        let mut args = self.params.values.to_args();
        let image = &self.image;
        let numbers = [("--width", image.width), ("--height", image.height)];
        args.extend(numbers.into_iter().filter_map(|(f, v)| v.map(|v| [f.to_owned(), v.to_string()])).flatten());
        if image.no_png {
            args.push("--no-png".into());
        }
        let l = &self.lights;
        let xyz = |v: [f32; 3]| v.show();
        let lights = [
            ("--sun", l.sun.map(xyz)),
            ("--sun-irradiance", l.sun_irradiance.map(xyz)),
            ("--sun-diameter", l.sun_diameter.map(|v| v.to_string())),
            ("--sky-strength", l.sky_strength.map(|v| v.to_string())),
            ("--sky-rotation", l.sky_rotation.map(|v| v.to_string())),
        ];
        args.extend(lights.into_iter().filter_map(|(f, v)| v.map(|v| [f.to_owned(), v])).flatten());
        if let Some(sky) = &l.sky {
            let path = sky.canonicalize().with_context(|| format!("--sky {}", sky.display()))?;
            args.extend(["--sky".to_owned(), path.display().to_string()]);
        }
        Ok(args)
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

impl EngineFlags {
    /// The flags given, as a command line takes them (not `--device`: a job's node has its own devices).
    pub fn to_args(&self) -> Vec<String> {
        let mut args = vec!["--in-flight".to_owned(), self.in_flight.to_string()];
        if let Some(mib) = self.memory_budget {
            args.extend(["--memory-budget".to_owned(), mib.to_string()]);
        }
        if let Some(value) = self.strategy.to_possible_value() {
            args.extend(["--strategy".to_owned(), value.get_name().to_owned()]);
        }
        args
    }
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
    /// Write a tone-mapped sRGB PNG beside the EXR (the default)
    #[arg(long, overrides_with = "no_png")]
    pub png: bool,
    /// Do not write the PNG
    #[arg(long, overrides_with = "png")]
    pub no_png: bool,
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

/// Two whole numbers written around `separator` (`3/4`, `0..24`), for flags that name a part of a whole.
pub fn two_numbers(text: &str, separator: &str) -> Option<(u32, u32)> {
    let (a, b) = text.split_once(separator)?;
    Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
}

fn parse_xyz(s: &str) -> Result<[f32; 3], String> {
    let values: Result<Vec<f32>, _> = s.split(',').map(|p| p.trim().parse::<f32>()).collect();
    match values {
        Ok(v) if v.len() == 3 => Ok([v[0], v[1], v[2]]),
        _ => Err(format!("expected X,Y,Z, got '{s}'")),
    }
}
