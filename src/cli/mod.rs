//! Sub-commands. Each parses its flags here and hands the library a scene and parameters.

mod args;
mod bench;
mod compare;
mod devices;
mod metrics;
mod reference;
mod render;

use std::path::Path;
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::{Context as _, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use sensorlight::gbuffer::GBufferData;
use sensorlight::output::exr::ExrImage;
use sensorlight::params::{Overrides, ParamError, RenderParams};
use sensorlight::renderer::Progress;
use sensorlight::scene::Scene;
use sensorlight::strategy::Event;
use sensorlight::vk::{Device, DeviceOptions};

#[derive(Parser)]
#[command(name = "sensorlight", version, about = "Global illumination by Sensor-Based Lighting on Vulkan")]
#[command(after_help = "Set SENSORLIGHT_VALIDATION=1 to run under the Khronos validation layer; \
    any message it reports then makes the exit code 3.")]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the Vulkan devices, their drivers and the limits that matter here.
    Devices,
    /// Render a scene to an EXR.
    Render(render::RenderArgs),
    /// Compute the CPU reference image of the same estimator by ray casting (no GPU needed).
    Reference(reference::ReferenceArgs),
    /// Compare an image with a reference image: relative RMSE, mean error and bias over lit pixels.
    Compare(compare::CompareArgs),
    /// Benchmark the sensor batching strategies against each other and the raw fill rate.
    Bench(bench::BenchArgs),
    /// Reproduce the paper's metrics (Table I, Fig. 10, Fig. 11) on this device.
    Metrics(metrics::MetricsArgs),
}

pub fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Devices => devices::run(),
        Command::Render(args) => render::run(args),
        Command::Reference(args) => reference::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Metrics(args) => metrics::run(args),
    }
}

/// Loads the scene at `path` and resolves the parameters: `flags` over its `[render]` table over the
/// defaults. Prints the scene's warnings.
fn load_scene(path: &Path, flags: &Overrides) -> Result<(Scene, RenderParams)> {
    let scene = Scene::load(path)?;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    let from_file = Overrides::from_scene_table(path, &scene.render)?;
    let params = RenderParams::resolve(Some((path, &from_file)), flags)?;
    for warning in params.warnings(scene.mesh.brightest_emission()) {
        eprintln!("warning: {warning}");
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

/// Checks, before any work, that an EXR output and what is written beside it (the PNG preview unless
/// `png` is false, `extra` files with the flag that names each) can be written, and that none of them is
/// another or one of `inputs`.
fn check_exr_outputs(exr: &Path, png: bool, extra: &[(&str, &Path)], inputs: &[&Path]) -> Result<()> {
    sensorlight::output::atomic::check_extension(exr, "exr")?;
    let png = png.then(|| exr.with_extension("png"));
    let mut outputs = vec![("-o", exr)];
    outputs.extend(png.as_deref().map(|p| ("the PNG preview", p)));
    outputs.extend_from_slice(extra);
    sensorlight::output::atomic::check_outputs(&outputs, inputs)
}

/// Exit code when the validation layer reported anything.
const EXIT_VALIDATION: u8 = 3;

/// Opens the device (`--device N` or the best one), says which, runs `work`, closes the device, and turns
/// validation messages into a non-zero exit.
fn with_device(device_index: Option<usize>, work: impl FnOnce(&Arc<Device>) -> Result<()>) -> Result<ExitCode> {
    let options = DeviceOptions::from_env(device_index, sensorlight::passes::requirements());
    let device = match device_index {
        Some(i) => Device::new(&options).with_context(|| format!("--device {i} (see `sensorlight devices`)"))?,
        None => Device::new(&options)?,
    };
    eprintln!("device: {}", device.adapter);
    let log = device.validation_log().clone();
    let result = work(&device);
    drop(device);
    result?;
    let messages = log.messages();
    if !messages.is_empty() {
        eprintln!("error: the validation layer reported {} message(s)", messages.len());
        return Ok(ExitCode::from(EXIT_VALIDATION));
    }
    Ok(ExitCode::SUCCESS)
}

/// Says what the strategy choice found worth saying: refusals, and what `auto` measured.
fn report_strategy_event(event: Event) {
    match event {
        Event::Checked { strategy, result, cached } if !result.passed => {
            let how = if cached { "self-check (cached)" } else { "self-check" };
            eprintln!(
                "{how}: {strategy} vs per-sensor: max difference {:.2e} of the brightest R: FAILS (refused on this device)",
                result.max_difference
            );
        }
        Event::Measured { rd, per_sensor } => {
            let timings: Vec<String> =
                per_sensor.iter().map(|(k, t)| format!("{k} {:.3} ms", t.as_secs_f64() * 1e3)).collect();
            eprintln!("auto: per sensor at rd {rd}: {}", timings.join(", "));
        }
        Event::Unsupported { strategy, why } => eprintln!("{strategy}: unsupported here ({why})"),
        Event::Checked { .. } => {}
    }
}

/// Sensors rendered so far, on a progress bar whose length grows as refinement rounds add sensors.
struct SensorBar(ProgressBar);

impl Progress for SensorBar {
    fn queued(&self, n: u64) {
        self.0.inc_length(n);
    }
    fn done(&self, n: u64) {
        self.0.inc(n);
    }
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
/// The G-buffer channels that let `compare` mask what it should not judge: `surface_id` (silhouettes) and
/// `emission.*` (emitters, whose `Le` is given, not estimated).
fn gbuffer_aovs(exr: ExrImage, g: &GBufferData) -> ExrImage {
    exr.rgb("emission", &g.emission).scalar("surface_id", g.surface.iter().map(|&s| s as f32).collect())
}

fn progress_bar(total: u64, unit: &str) -> ProgressBar {
    let bar = ProgressBar::new(total);
    let template = format!("{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {unit} ({{eta}} left)");
    let style = ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style.progress_chars("=> "));
    bar
}
