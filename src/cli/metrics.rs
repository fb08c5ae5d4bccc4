//! `sensorlight metrics`: the paper's Table I, Fig. 10 and Fig. 11 on this device.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context as _, Result, bail, ensure};
use clap::Args;
use sensorlight::cancel::{Cancel, Reason};
use sensorlight::metrics::{self, MetricsConfig, report};
use sensorlight::params::flags::{FlagSet, ParamFlags};
use sensorlight::params::{
    DEFAULT_EPSILON, DEFAULT_FILTER_RADIUS, EstimatorKind, Overrides, Param, RenderParams, SensorShape,
};
use sensorlight::renderer::Progress;
use sensorlight::scene::ImageSize;
use sensorlight::strategy::{Cache, StrategyRequest};

#[derive(Args)]
// `render`'s flags, said as they act here: the paper's model and estimator, no mesh lit by a white sky.
#[command(mut_arg("sensor", |a| a.help(format!("Sensor kind [default: {}, the paper's]", SensorShape::Frustum))))]
#[command(mut_arg("epsilon", |a| a.help(format!(
    "ε of the paper's model: non-emitters seen by a sensor return Kd·ε (≥ 0; 0 = direct light only) [default: \
     {DEFAULT_EPSILON}]"
))))]
#[command(mut_arg("background", |a| a.help("Radiance of rays leaving the scene, as R,G,B [default: 0,0,0]")))]
#[command(mut_arg("filter_radius", |a| a.help(format!(
    "Radius of the id-constrained Gaussian filter in pixels (0 = off) [default: {} with the paper's estimator, {} \
     with --estimator exact]",
    DEFAULT_FILTER_RADIUS.paper, DEFAULT_FILTER_RADIUS.exact
))))]
pub struct MetricsArgs {
    /// Output directory (created if needed): CSV, Markdown, SVG and PNG per experiment, and metrics.json
    #[arg(short, long)]
    output: PathBuf,
    #[arg(long, value_enum, help = format!("How R is read from the sensor maps [default: {}]", EstimatorKind::Paper))]
    estimator: Option<EstimatorKind>,
    /// Table I: sensor time against screen resolution (all three when none of these is given)
    #[arg(long)]
    table1: bool,
    /// Fig. 10: sensor time against sensor map size
    #[arg(long)]
    fig10: bool,
    /// Fig. 11: number of sensors against sensor map size (from the same renders as Fig. 10)
    #[arg(long)]
    fig11: bool,
    #[arg(long, help = format!("Scene file (TOML) [default: {DEFAULT_SCENE} of the source tree it was built from]"))]
    scene: Option<PathBuf>,
    /// Sensor map size of Table I [default: 256, as the paper; 32 with --quick]
    #[arg(long)]
    sensor_size: Option<u32>,
    /// Sensor map sizes of the figures, comma-separated [default: 16,32,64,128,256]
    #[arg(long, value_delimiter = ',')]
    sizes: Vec<u32>,
    /// Screen resolutions of Table I, e.g. 200x200,300x200 [default: the paper's 13]
    #[arg(long, value_delimiter = ',', value_parser = parse_resolution)]
    resolutions: Vec<ImageSize>,
    /// Screen resolutions of the figures [default: 320x240,640x480,1024x768]
    #[arg(long, value_delimiter = ',', value_parser = parse_resolution)]
    figure_resolutions: Vec<ImageSize>,
    /// A reduced run (small resolutions and maps): a minute or two on a CPU driver
    #[arg(long)]
    quick: bool,
    #[command(flatten)]
    params: ParamFlags<MetricsParams>,
    /// Batching strategy: auto or a name (see `render --help`)
    #[arg(long, value_enum, default_value_t = StrategyRequest::Auto)]
    strategy: StrategyRequest,
    /// Device index from `sensorlight devices` [default: the best available]
    #[arg(long)]
    device: Option<usize>,
}

/// What `metrics` takes of the parameters as `render` does; its estimator and map size are its own.
pub enum MetricsParams {}

impl FlagSet for MetricsParams {
    const PARAMS: &'static [Param] = &[
        Param::Sensor,
        Param::Fov,
        Param::Epsilon,
        Param::Background,
        Param::Tile,
        Param::Dradiance,
        Param::FilterRadius,
    ];
}

fn parse_resolution(s: &str) -> Result<ImageSize, String> {
    let (w, h) = s.split_once('x').ok_or_else(|| format!("expected WIDTHxHEIGHT, got '{s}'"))?;
    let (width, height) = (w.parse::<u32>(), h.parse::<u32>());
    match (width, height) {
        (Ok(width), Ok(height)) if width > 0 && height > 0 => Ok(ImageSize { width, height }),
        _ => Err(format!("expected WIDTHxHEIGHT with positive integers, got '{s}'")),
    }
}

/// The scene of the metrics when none is given, relative to the source tree.
const DEFAULT_SCENE: &str = "scenes/cornell/cornell.toml";

/// The default scene, found in the source tree the binary was built from (`CARGO_MANIFEST_DIR` at build
/// time), so that `metrics` runs from any directory, and an installed binary says what is missing.
fn default_scene() -> Result<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_SCENE);
    if !path.is_file() {
        bail!(
            "no --scene given, and the default scene {} (in the source tree this binary was built from) is not \
             there; pass --scene SCENE.toml",
            path.display()
        );
    }
    Ok(path)
}

/// The renders' progress as the counter of renders shows it; they stop, between batches, once interrupted.
struct Interruptible(Cancel);

impl Progress for Interruptible {
    fn cancelled(&self) -> Option<Reason> {
        self.0.reason()
    }
}

pub fn run(args: MetricsArgs) -> Result<ExitCode> {
    let cancel = Cancel::on_signals().context("cannot handle SIGINT and SIGTERM")?;
    let scene_path = match &args.scene {
        Some(path) => path.clone(),
        None => default_scene()?,
    };
    // Recorded as given, the default as the source tree names it: the same command writes the same bytes
    // wherever the tree lies.
    let scene_name = args.scene.as_ref().map_or_else(|| DEFAULT_SCENE.to_owned(), |p| p.display().to_string());
    ensure!(
        !args.output.exists() || args.output.is_dir(),
        "-o {}: exists and is not a directory",
        args.output.display()
    );
    let scene = super::load_scene_file(&scene_path)?;
    let from_file = Overrides::from_scene_table(&scene_path, &scene.render)?;
    // The paper's sensor and map size unless the command line or the scene says otherwise.
    // The paper's experiment: its estimator, sensor and map size unless told otherwise.
    let from_file = Overrides {
        estimator: from_file.estimator.or(Some(EstimatorKind::Paper)),
        sensor: from_file.sensor.or(Some(SensorShape::Frustum)),
        sensor_size: from_file.sensor_size.or(Some(if args.quick { 32 } else { 256 })),
        ..from_file
    };
    let overrides =
        Overrides { estimator: args.estimator, sensor_size: args.sensor_size, ..args.params.values.clone() };
    let params = RenderParams::resolve(Some((&scene_path, &from_file)), &overrides)?;
    let mut config = MetricsConfig::new(scene_name, params.clone());
    if args.quick {
        config = config.quick();
    }
    config.table1_sensor_size = params.values.sensor_size;
    if !args.sizes.is_empty() {
        config.figure_sizes = args.sizes.clone();
    }
    if !args.resolutions.is_empty() {
        config.table1_resolutions = args.resolutions.clone();
    }
    if !args.figure_resolutions.is_empty() {
        config.figure_resolutions = args.figure_resolutions.clone();
    }
    let all = !(args.table1 || args.fig10 || args.fig11);
    config.table1 = all || args.table1;
    config.figures = all || args.fig10 || args.fig11;
    config.strategy = args.strategy;
    ensure!(config.figure_sizes.iter().all(|&rd| rd >= 2), "--sizes must be at least 2");

    super::with_device(args.device, |device| {
        let runs = config.runs();
        let overall = super::counter::Counter::new(runs.len() as u64, "renders");
        let start = Instant::now();
        let mut cache = Cache::open_default();
        // The bar counts renders; sensors within a render are not shown.
        let results = metrics::run(device, &scene, &config, &mut cache, &Interruptible(cancel), &mut |run| {
            let s = &run.stats;
            overall.suspend(|| {
                say!(
                    "{:?} {}x{} rd {} ({}): {} sensors, {:.4} ms/sensor, {:.1} s",
                    run.experiment,
                    s.width,
                    s.height,
                    s.sensor_size,
                    s.strategy,
                    s.sensors,
                    s.sensor_time_ms,
                    s.total_seconds
                )
            });
            overall.inc(1);
        })?;
        overall.finish();
        let header = report::Header {
            device: &device.adapter.name,
            driver: &device.adapter.driver,
            config: &config,
            total_seconds: start.elapsed().as_secs_f64(),
        };
        let files = report::write(&args.output, &header, &results).context("writing the metrics")?;
        say!("{} renders in {:.1} s; wrote:", results.len(), header.total_seconds);
        for f in files {
            say!("  {}", f.display());
        }
        Ok(())
    })
}
