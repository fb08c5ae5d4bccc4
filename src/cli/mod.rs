//! Sub-commands. Each parses its flags here and hands the library a scene and parameters.

/// `eprintln!` unless `-q` (see `say`).
macro_rules! say {
    ($($arg:tt)*) => {
        if $crate::cli::say::normal() {
            sensorlight::errln!($($arg)*);
        }
    };
}

mod args;
mod bake;
mod bench;
mod cache;
mod compare;
mod counter;
mod devices;
mod frames;
mod metrics;
mod progress;
mod reference;
mod render;
mod say;
mod slurm;
mod tiles;
mod view;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::{Context as _, Result, bail, ensure};
use args::LightFlags;
use clap::{Parser, Subcommand};
use sensorlight::gbuffer::GBufferData;
use sensorlight::output::exr::ExrImage;
use sensorlight::params::{Overrides, ParamError, RenderParams};
use sensorlight::scene::{FileKind, ImageSize, Mesh, Scene, auto_camera};
use sensorlight::strategy::Event;
use sensorlight::vk::{Device, DeviceOptions};

#[derive(Parser)]
#[command(name = "sensorlight", version, about = "Global illumination by Sensor-Based Lighting on Vulkan")]
#[command(after_help = "Set SENSORLIGHT_VALIDATION=1 to run under the Khronos validation layer; \
    any message it reports then makes the exit code 3.")]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Say more on standard error where there is more to say: render, bench and metrics name the device;
    /// render and bench show the strategy's self-checks and measurements, render its per-round statistics;
    /// devices, reference and compare have nothing more to say
    #[arg(short, long, global = true, conflicts_with = "quiet", display_order = 1000)]
    verbose: bool,
    /// Say nothing on standard error but errors (no warnings, no progress); results on standard output (compare's
    /// figures, devices' list) are printed all the same
    #[arg(short, long, global = true, display_order = 1000)]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// List the Vulkan devices, their drivers and the limits that matter here.
    Devices,
    /// Render a scene to an EXR.
    Render(render::RenderArgs),
    /// Solve the radiance cache once and write it to a file that `render --cache` and `view --cache` read.
    Cache(cache::CacheArgs),
    /// Join the tiles of `render --image-tile I/N` into the image the single render writes, bit for bit.
    Assemble(tiles::AssembleArgs),
    /// Split a render over a Slurm cluster: a cache job, a job array of tiles or frames, a join job.
    Slurm(slurm::SlurmArgs),
    /// Compute the CPU reference image of the same estimator by ray casting (no GPU needed).
    Reference(reference::ReferenceArgs),
    /// Compare an image with a reference image: relative RMSE, mean error and bias over lit pixels.
    Compare(compare::CompareArgs),
    /// Benchmark the sensor batching strategies against each other and the raw fill rate.
    Bench(bench::BenchArgs),
    /// Reproduce the paper's metrics (Table I, Fig. 10, Fig. 11) on this device.
    Metrics(metrics::MetricsArgs),
    /// Bake a lightmap onto every surface: a glTF binary (.glb) with TEXCOORD_1 and the lightmap EXR beside it.
    Bake(bake::BakeArgs),
    /// Watch a scene render in a window: it converges round by round and starts again as the camera moves.
    View(view::ViewArgs),
}

pub fn run(cli: Cli) -> Result<ExitCode> {
    say::set(match (cli.quiet, cli.verbose) {
        (true, _) => say::Verbosity::Quiet,
        (_, true) => say::Verbosity::Verbose,
        _ => say::Verbosity::Normal,
    });
    match cli.command {
        Command::Devices => devices::run(),
        Command::Render(args) => render::run(args),
        Command::Cache(args) => cache::run(args),
        Command::Assemble(args) => tiles::run(args),
        Command::Slurm(args) => slurm::run(args),
        Command::Reference(args) => reference::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Metrics(args) => metrics::run(args),
        Command::View(args) => view::run(args),
        Command::Bake(args) => bake::run(args),
    }
}

/// Loads the scene file at `path` and prints its warnings. A mesh given instead is told how to get a scene.
fn load_scene_file(path: &Path) -> Result<Scene> {
    let kind = FileKind::of(path);
    if kind.is_mesh() {
        bail!(
            "{} is {}; this command needs a scene file (TOML). `sensorlight render {} -o out.exr \
             --write-scene SCENE.toml` writes one, with a camera that frames the mesh",
            path.display(),
            kind.describe(),
            path.display()
        );
    }
    let scene = Scene::load(path)?;
    warn_all(&scene.warnings);
    Ok(scene)
}

fn warn_all(warnings: &[String]) {
    if say::normal() {
        for warning in warnings {
            sensorlight::errln!("warning: {warning}");
        }
    }
}

/// Loads the scene file at `path` and resolves the parameters: `flags` over its `[render]` table over the
/// defaults. Prints the scene's warnings.
fn load_scene(path: &Path, flags: &Overrides) -> Result<(Scene, RenderParams)> {
    let scene = load_scene_file(path)?;
    resolve(scene, flags)
}

fn resolve(scene: Scene, flags: &Overrides) -> Result<(Scene, RenderParams)> {
    let from_file = Overrides::from_scene_table(&scene.path, &scene.render)?;
    let params = RenderParams::resolve(Some((&scene.path, &from_file)), flags)?;
    warn_all(&params.warnings(scene.mesh.brightest_emission()));
    Ok((scene, params))
}

/// Loads what `path` holds: a scene file, or an OBJ mesh, given a camera that frames it, an image of
/// `width` × `height` (each by default the automatic camera's), and, if nothing in it emits, a white sky
/// (background 1,1,1: the image is then never black); lit by the sun and sky map `lights` asks for. Anything else is named
/// and refused.
fn load_input(
    path: &Path,
    flags: &Overrides,
    (width, height): (Option<u32>, Option<u32>),
    lights: &LightFlags,
) -> Result<(Scene, RenderParams)> {
    let (scene, params) = match FileKind::of(path) {
        FileKind::Scene => {
            let mut scene = Scene::load(path)?;
            lights.apply(&mut scene)?;
            warn_all(&scene.warnings);
            if say::normal() {
                scene.notes.iter().for_each(|note| sensorlight::errln!("note: {note}"));
            }
            resolve(scene, flags)
        }
        FileKind::ObjMesh | FileKind::GltfMesh => {
            let default = auto_camera::DEFAULT_IMAGE;
            let size = ImageSize {
                // Zero is refused by the flags' own check, with the flag's name.
                width: width.filter(|&w| w > 0).unwrap_or(default.width),
                height: height.filter(|&h| h > 0).unwrap_or(default.height),
            };
            let mut scene = Scene::from_mesh(path, size)?;
            lights.apply(&mut scene)?;
            if !scene.mesh.emits_light() && scene.sky.is_none() {
                scene.warnings.retain(|w| w != Mesh::NO_EMITTER);
                let white = toml::Value::Array(vec![toml::Value::Float(1.0); 3]);
                scene.render.insert("background".into(), white);
                if say::normal() && flags.background.is_none() {
                    sensorlight::errln!(
                        "note: nothing in {} emits light: it is lit by a white sky (--background 1,1,1; the flag \
                         changes it)",
                        path.display()
                    );
                }
            }
            warn_all(&scene.warnings);
            if say::normal() {
                scene.notes.iter().for_each(|note| sensorlight::errln!("note: {note}"));
            }
            resolve(scene, flags)
        }
        kind => {
            bail!("{} is {}; expected a scene file (TOML), or an OBJ or glTF mesh", path.display(), kind.describe())
        }
    }?;
    if let Some(sky) = scene.sky.as_ref().filter(|_| params.estimator.background != glam::Vec3::ZERO) {
        bail!(
            "{}: the sky map {} and the constant background (--background, or the scene's [render] background) \
             both say what rays leaving the scene see: give one",
            scene.path.display(),
            sky.name
        );
    }
    Ok((scene, params))
}

/// Names a [`ParamError`] found by the library (e.g. a device limit) as the user set the value.
fn attribute(params: &RenderParams, error: anyhow::Error) -> anyhow::Error {
    match error.downcast::<ParamError>() {
        Ok(e) => params.attribute(e).into(),
        Err(other) => other,
    }
}

/// What `-o` names, by its extension: `F.exr` the EXR of linear radiance and, unless `--no-png`, the
/// tone-mapped `F.png` beside it; `F.png` the PNG alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OutputKind {
    Exr,
    Png,
}

impl OutputKind {
    fn of(path: &Path) -> Result<Self> {
        ensure!(
            path != Path::new("-"),
            "-o -: standard output is not supported (the files are staged and renamed into place whole); name an \
             .exr or a .png file"
        );
        let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match extension.as_deref() {
            Some("exr") => Ok(OutputKind::Exr),
            Some("png") => Ok(OutputKind::Png),
            _ => bail!(
                "{}: expected an .exr file name (the EXR of linear radiance, with a tone-mapped PNG beside it) or a \
                 .png one (the PNG alone)",
                path.display()
            ),
        }
    }
}

/// The image files a render (or reference) writes, from `-o` and `--png`/`--no-png`.
struct ImageOutputs {
    exr: Option<PathBuf>,
    png: Option<PathBuf>,
}

impl ImageOutputs {
    fn new(output: &Path, png: bool) -> Result<Self> {
        match OutputKind::of(output)? {
            OutputKind::Exr => {
                Ok(Self { exr: Some(output.to_owned()), png: png.then(|| output.with_extension("png")) })
            }
            OutputKind::Png => {
                ensure!(png, "--no-png with -o {}: nothing would be written; name an .exr output", output.display());
                Ok(Self { exr: None, png: Some(output.to_owned()) })
            }
        }
    }

    /// Checks, before any work, that these outputs and `extra` (with the flag that names each) can be written,
    /// and that none of them is another or one of `inputs`.
    fn check(&self, extra: &[(&str, &Path)], inputs: &[&Path]) -> Result<()> {
        let mut outputs: Vec<(&str, &Path)> = Vec::new();
        outputs.extend(self.exr.as_deref().map(|p| ("-o", p)));
        let png_flag = if self.exr.is_some() { "the PNG beside the EXR" } else { "-o" };
        outputs.extend(self.png.as_deref().map(|p| (png_flag, p)));
        outputs.extend_from_slice(extra);
        sensorlight::output::atomic::check_outputs(&outputs, inputs)
    }

    /// The files, in the order written.
    fn paths(&self) -> impl Iterator<Item = &PathBuf> {
        self.exr.iter().chain(&self.png)
    }
}

/// Exit code when the validation layer reported anything.
const EXIT_VALIDATION: u8 = 3;

/// Opens the device (`--device N` or the best one), says which, runs `work`, closes the device, and turns
/// validation messages into a non-zero exit.
fn with_device(device_index: Option<usize>, work: impl FnOnce(&Arc<Device>) -> Result<()>) -> Result<ExitCode> {
    let device = open_device(DeviceOptions::from_env(device_index, sensorlight::passes::requirements()))?;
    let log = device.validation_log().clone();
    let result = work(&device);
    drop(device);
    validated(&log, result)
}

/// Opens the device `options` asks for (`--device N` or the best one) and, with `-v`, says which.
fn open_device(options: DeviceOptions) -> Result<Arc<Device>> {
    let device = match options.device_index {
        Some(i) => Device::new(&options).with_context(|| format!("--device {i} (see `sensorlight devices`)"))?,
        None => Device::new(&options)?,
    };
    if say::verbose() {
        sensorlight::errln!("device: {}", device.adapter);
    }
    Ok(device)
}

/// `result` of work on a device now closed, with the validation layer's messages (`log`) made an error
/// exit.
fn validated(log: &sensorlight::vk::validation::ValidationLog, result: Result<()>) -> Result<ExitCode> {
    // Said whether the work failed or not: a render stopped part-way must tear down as cleanly as one done.
    let messages = log.messages();
    if !messages.is_empty() {
        sensorlight::errln!("error: the validation layer reported {} message(s)", messages.len());
    }
    result?;
    if !messages.is_empty() {
        return Ok(ExitCode::from(EXIT_VALIDATION));
    }
    Ok(ExitCode::SUCCESS)
}

/// The renderer `render` and `view` use for `scene` with `params`, as `engine` says; strategy events go to
/// `report`.
fn build_renderer(
    device: &Arc<Device>,
    (scene, params): (&Scene, &RenderParams),
    engine: &args::EngineFlags,
    cache: &mut sensorlight::strategy::Cache,
    report: &mut dyn FnMut(Event),
) -> Result<sensorlight::renderer::Renderer> {
    sensorlight::renderer::Renderer::builder(device, scene, params.estimator.sensor, params.values.sensor_size)
        .estimator(params.values.estimator)
        .radiance_cache(sensorlight::renderer::CacheConfig::for_params(params))
        .memory_budget(engine.memory_budget.map(|mib| mib << 20))
        .in_flight(engine.in_flight)
        .strategy(engine.strategy)
        .cache(cache)
        .on_strategy_event(report)
        .build()
        .map_err(|e| attribute(params, e))
}

/// What the strategy choice found, for `-v`: refusals (multiview on lavapipe 22.3, a driver bug, is no
/// concern of a user who did not ask), and what `auto` measured.
fn strategy_event_text(event: &Event) -> Option<String> {
    match event {
        Event::Checked { strategy, result, cached } if !result.passed => {
            let how = if *cached { "self-check (cached)" } else { "self-check" };
            Some(format!(
                "{how}: {strategy} vs per-sensor: max difference {:.2e} of the brightest R: fails, not used on this \
                 device",
                result.max_difference
            ))
        }
        Event::Measured { rd, per_sensor } => {
            let timings: Vec<String> =
                per_sensor.iter().map(|(k, t)| format!("{k} {:.3} ms", t.as_secs_f64() * 1e3)).collect();
            Some(format!("auto: per sensor at rd {rd}: {}", timings.join(", ")))
        }
        Event::Unsupported { strategy, why } => Some(format!("{strategy}: unsupported here ({why})")),
        Event::Checked { .. } => None,
    }
}

/// The G-buffer channels that let `compare` mask what it should not judge: `surface_id` (silhouettes) and
/// `emission.*` (emitters, whose `Le` is given, not estimated); and what a denoiser (Open Image Denoise)
/// takes beside the beauty pass: `albedo.R/G/B` (the material's `Kd`), `normal.X/Y/Z` (the unit shading
/// normal, world space, turned towards the camera; the mesh is flat-shaded, so the face's) and `depth.Z` (the
/// distance from `eye` to the visible point along the pixel's ray). All are 0 where no surface is (`A` 0).
fn gbuffer_aovs(exr: ExrImage, g: &GBufferData, eye: glam::Vec3) -> ExrImage {
    let depth = g.position.iter().map(|p| if p.w > 0.0 { (p.truncate() - eye).length() } else { 0.0 });
    let normal: Vec<[f32; 3]> = g.normal.iter().map(|n| n.truncate().to_array()).collect();
    exr.rgb("emission", &g.emission)
        .scalar("surface_id", g.surface.iter().map(|&s| s as f32).collect())
        .rgb("albedo", &g.albedo)
        .xyz("normal", &normal)
        .scalar("depth.Z", depth.collect())
}

/// Above this share of lit pixels brighter than white at a scene file's default exposure, the PNG takes the
/// automatic exposure instead: the image would be mostly clipped (a bright lamp, an exposure never set).
const CLIPPED_AT_MOST: f64 = 0.01;

/// How the PNG's exposure is chosen: `--exposure` or a scene file's `exposure` where set (`Set`). Else, for
/// a bare mesh (`Mesh`), the exposure that maps the 99th percentile of its lit pixels' luminance to white
/// (`png::auto_exposure`; lit: a surface, not an emitter's front, above 0), so that a dim mesh's PNG is not
/// black; for a scene file (`Default`) the default, unless more than [`CLIPPED_AT_MOST`] of its lit pixels
/// would clip, then the automatic one. A tile records its rule, so that `assemble` chooses as `render` does.
#[derive(Clone, Copy, Debug, PartialEq)]
enum ExposureRule {
    Set(f32),
    Default(f32),
    Mesh(f32),
}

impl ExposureRule {
    fn of(params: &RenderParams, input: &Path) -> Self {
        use sensorlight::params::{Origin, Param};
        let stops = params.values.exposure;
        if params.origin(Param::Exposure) != Origin::Default {
            Self::Set(stops)
        } else if FileKind::of(input).is_mesh() {
            Self::Mesh(stops)
        } else {
            Self::Default(stops)
        }
    }

    /// As a tile's header says it: `set 1.5`, `default 0`, `mesh 0`.
    fn text(self) -> String {
        match self {
            Self::Set(x) => format!("set {x}"),
            Self::Default(x) => format!("default {x}"),
            Self::Mesh(x) => format!("mesh {x}"),
        }
    }

    fn parse(text: &str) -> Option<Self> {
        let (kind, stops) = text.split_once(' ')?;
        let stops: f32 = stops.parse().ok()?;
        match kind {
            "set" => Some(Self::Set(stops)),
            "default" => Some(Self::Default(stops)),
            "mesh" => Some(Self::Mesh(stops)),
            _ => None,
        }
    }

    /// The exposure in stops for `image`, whose pixel i shows a surface (not an emitter's front) where
    /// `lit(i)`, and, when it was chosen automatically, what the summary says of it.
    fn choose(self, image: &[glam::Vec4], lit: impl Fn(usize) -> bool) -> (f32, Option<String>) {
        use sensorlight::output::png;
        let stops = match self {
            Self::Set(x) => return (x, None),
            Self::Default(x) | Self::Mesh(x) => x,
        };
        let lit: Vec<f32> = (image.iter().enumerate())
            .filter(|(i, _)| lit(*i))
            .map(|(_, p)| png::luminance(*p))
            .filter(|&y| y > 0.0 && y.is_finite())
            .collect();
        let clipped = lit.iter().filter(|&&y| y * stops.exp2() > 1.0).count() as f64 / lit.len().max(1) as f64;
        let why = match self {
            Self::Mesh(_) => String::new(),
            _ if clipped > CLIPPED_AT_MOST => {
                format!("at the default {stops}, {:.0} % of lit pixels would clip white; ", 100.0 * clipped)
            }
            _ => return (stops, None),
        };
        match png::auto_exposure(lit) {
            Some(auto) => {
                let sets = if why.is_empty() { "--exposure" } else { "the scene file's `exposure` or --exposure" };
                (auto, Some(format!("exposure {auto:.1} (auto: {why}99th percentile of lit pixels; {sets} sets it)")))
            }
            None => (stops, None),
        }
    }
}

/// The PNG's exposure in stops for `params` and `input` ([`ExposureRule`]) over `image` and its G-buffer.
fn png_exposure(params: &RenderParams, input: &Path, image: &[glam::Vec4], g: &GBufferData) -> (f32, Option<String>) {
    let lit = |i: usize| g.surface[i] != sensorlight::scene::NO_SURFACE && g.emission[i].truncate() == glam::Vec3::ZERO;
    ExposureRule::of(params, input).choose(image, lit)
}
