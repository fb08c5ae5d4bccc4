//! `sensorlight view`: the scene in a window (the library's `viewer`), with `render`'s flags for what the
//! image is and how the renderer runs, so that the window shows what `render` writes.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::{Context as _, Result, bail, ensure};
use clap::Args;
use sensorlight::cancel::{Cancel, Reason};
use sensorlight::gi::file::CacheFile;
use sensorlight::output::atomic;
use sensorlight::params::RenderParams;
use sensorlight::renderer::{RenderOutput, Renderer};
use sensorlight::scene::{Camera, Scene};
use sensorlight::strategy::{Cache, Event};
use sensorlight::viewer::{self, ViewHost, ViewSetup, script};
use sensorlight::vk::validation::ValidationLog;
use sensorlight::vk::{Device, DeviceOptions, WindowTarget};

use super::args::{EngineFlags, LookFlags};
use super::{ImageOutputs, OutputKind, say};

#[derive(Args)]
pub struct ViewArgs {
    /// Scene file (TOML), or an OBJ or glTF mesh, framed by an automatic camera as `render` frames it.
    /// In the window: left drag orbits, right or middle drag pans, the wheel dollies; + and - change the
    /// exposure (0 resets it); 1 to 5 show the image, R, the sensors, the surfaces, the emission; s saves;
    /// r goes back to the scene's camera; p plays the scene's camera path ([path]), a frame as each render is
    /// done, and stops it; q or Esc quits
    scene: PathBuf,
    /// Where `s` saves: F.exr with the AOVs `render --aovs` writes, and F.png beside it (each save replaces
    /// them, all or none)
    #[arg(short, long, value_name = "F.exr", default_value = "view.exr")]
    output: PathBuf,
    #[command(flatten)]
    look: LookFlags,
    #[command(flatten)]
    engine: EngineFlags,
    #[arg(long, value_name = "FILE", help = script_help())]
    script: Option<PathBuf>,
    /// Read the radiance cache from this file (`sensorlight cache`) instead of solving it
    #[arg(long, value_name = "FILE")]
    cache: Option<PathBuf>,
    /// Say each camera move's time to its first picture, and their median when the window closes
    #[arg(long)]
    timings: bool,
}

/// `--script`'s help, with the views `show` takes as the viewer names them.
fn script_help() -> String {
    let views: Vec<&str> = viewer::Show::ALL.iter().map(|s| s.word()).collect();
    format!(
        "Drive the window from a file of commands, one a line: wait done, wait round N, sync, orbit YAW PITCH, pan \
         X Y, dolly F, exposure STOPS, show VIEW ({}), save F.exr, resize WIDTH HEIGHT, frame K (of the scene's \
         camera path), play (the path, a frame a render; again: stop), quit (docs/DESIGN.md §12)",
        views.join(" | ")
    )
}

pub fn run(args: ViewArgs) -> Result<ExitCode> {
    // Before any work: where no window can be opened, the user learns it at once.
    check_display()?;
    let script = args.script.as_deref().map(script::load).transpose()?;
    ensure!(
        OutputKind::of(&args.output)? == OutputKind::Exr,
        "-o {}: the viewer saves an EXR (with a PNG beside it); name an .exr file",
        args.output.display()
    );
    let size = (args.look.image.width, args.look.image.height);
    let (scene, params) = super::load_input(&args.scene, &args.look.overrides(), size, &args.look.lights)?;
    if params.estimator.indirect.bounces().is_some() {
        super::warn_all(&sensorlight::gi::albedo_warnings(&scene.mesh));
    }
    let cache_file = args.cache.as_deref().map(|path| super::cache::read(path, &scene, &params)).transpose()?;
    let mut inputs = scene.input_paths();
    inputs.extend(args.cache.as_deref());
    ImageOutputs::new(&args.output, true)?.check(&[], &inputs)?;
    let size = args.look.image.size(&scene)?;
    let cancel = Cancel::on_signals().context("cannot handle SIGINT and SIGTERM")?;
    let name = args.scene.file_name().map_or_else(|| args.scene.display().to_string(), |n| n.to_string_lossy().into());
    let setup = ViewSetup {
        scene: &scene,
        size,
        frame: params.frame(),
        exposure: params.values.exposure,
        name,
        output: args.output.clone(),
        script,
        timings: args.timings,
    };
    let mut host = CliHost { args: &args, params: &params, inputs, cache_file, cancel, log: None };
    let result = viewer::run(setup, &mut host);
    match host.log {
        Some(log) => super::validated(&log, result),
        None => result.map(|()| ExitCode::SUCCESS),
    }
}

/// Refuses at once where no window system is named (on Unix but macOS: X11's `DISPLAY`, Wayland's
/// `WAYLAND_DISPLAY`), pointing to `render`.
fn check_display() -> Result<()> {
    let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    if cfg!(all(unix, not(target_os = "macos"))) && !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
        bail!(
            "no display to open a window on (neither DISPLAY nor WAYLAND_DISPLAY is set); `sensorlight render SCENE \
             -o out.exr` renders without one"
        );
    }
    Ok(())
}

/// The command line's side of the viewer: `render`'s device, renderer and files.
struct CliHost<'a> {
    args: &'a ViewArgs,
    params: &'a RenderParams,
    inputs: Vec<&'a Path>,
    /// `--cache`'s solution, checked against the scene.
    cache_file: Option<CacheFile>,
    cancel: Cancel,
    /// The device's validation log, once it is open.
    log: Option<Arc<ValidationLog>>,
}

impl ViewHost for CliHost<'_> {
    fn open(&mut self, window: WindowTarget) -> Result<Arc<Device>> {
        let options = DeviceOptions {
            window: Some(window),
            ..DeviceOptions::from_env(self.args.engine.device, sensorlight::passes::requirements())
        };
        let device = super::open_device(options)?;
        self.log = Some(device.validation_log().clone());
        Ok(device)
    }

    fn build(&mut self, device: &Arc<Device>, scene: &Scene) -> Result<Renderer> {
        let mut cache = Cache::open_default();
        let mut report = |event: Event| {
            if let (true, Some(text)) = (say::verbose(), super::strategy_event_text(&event)) {
                sensorlight::errln!("{text}");
            }
        };
        let mut renderer =
            super::build_renderer(device, (scene, self.params), &self.args.engine, &mut cache, &mut report)?;
        if let (Some(file), Some(path)) = (&self.cache_file, &self.args.cache) {
            super::cache::apply(&mut renderer, file, self.params, path)?;
        }
        Ok(renderer)
    }

    fn exposure(&self, output: &RenderOutput) -> Option<f32> {
        let (stops, auto) = super::png_exposure(self.params, &self.args.scene, &output.image, &output.gbuffer);
        auto.map(|_| stops)
    }

    fn save(&mut self, output: &RenderOutput, camera: &Camera, exposure: f32, path: &Path) -> Result<Vec<PathBuf>> {
        ensure!(
            OutputKind::of(path)? == OutputKind::Exr,
            "{}: the viewer saves an EXR (with a PNG beside it); name an .exr file",
            path.display()
        );
        let outputs = ImageOutputs::new(path, self.args.look.image.write_png())?;
        outputs.check(&[], &self.inputs)?;
        let mut files = atomic::Outputs::new();
        super::render::stage_images(&mut files, &outputs, output, (exposure, true), camera.eye)?;
        files.commit()?;
        Ok(outputs.paths().cloned().collect())
    }

    fn say(&self, line: &str) {
        if say::normal() {
            sensorlight::errln!("{line}");
        }
    }

    fn interrupted(&self) -> Option<Reason> {
        self.cancel.reason()
    }
}
