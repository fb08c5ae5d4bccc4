//! `sensorlight bench`: the sensor batching strategies against each other and against the raw fill rate;
//! with `--scenes`, time per sensor against the triangle count, full detail against clusters.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Result, ensure};
use clap::Args;
use sensorlight::bench::{self, BenchConfig, BenchEvent, BenchReport, MeshBenchConfig, MeshReport};
use sensorlight::outln;
use sensorlight::output::atomic;
use sensorlight::output::plot::{Chart, Series};
use sensorlight::params::flags::{FlagSet, ParamFlags};
use sensorlight::params::{Param, RenderParams};
use sensorlight::scene::{ImageSize, builtin};
use sensorlight::strategy::StrategyKind;

#[derive(Args)]
pub struct BenchArgs {
    /// Scene to place the sensors in [default: the built-in lightbox]
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Triangle-count axis: scenes to compare, comma-separated, the baseline first; each is timed at full
    /// detail and drawn from its clusters, with the first of --strategies [default: layered]
    #[arg(long, value_delimiter = ',', conflicts_with = "scene")]
    scenes: Vec<PathBuf>,
    /// With --scenes: time full detail only on meshes of at most this many triangles
    #[arg(long, default_value_t = 2_000_000, requires = "scenes")]
    full_detail_max: usize,
    /// With --scenes: also time the clusters drawn whole, without the triangle pass
    #[arg(long, requires = "scenes")]
    whole_clusters: bool,
    /// Sensor map sizes (rd), comma-separated
    #[arg(long, value_delimiter = ',', default_value = "32,64,128,256")]
    sizes: Vec<u32>,
    /// Strategies to compare, comma-separated [default: all]
    #[arg(long, value_enum, value_delimiter = ',')]
    strategies: Vec<StrategyKind>,
    /// Sensors per run
    #[arg(long, default_value_t = 256)]
    sensors: usize,
    /// Timed runs per strategy and size (after one warm-up run), interleaved
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    #[command(flatten)]
    params: ParamFlags<BenchParams>,
    /// Write the report as JSON
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write the measurements as CSV
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Plot sensors per second against rd (SVG)
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Device index from `sensorlight devices` [default: the best available]
    #[arg(long)]
    device: Option<usize>,
}

/// What `bench` takes of the parameters: what a sensor sees and how it is read.
pub enum BenchParams {}

impl FlagSet for BenchParams {
    const PARAMS: &'static [Param] = &[Param::Estimator, Param::Sensor, Param::Fov, Param::Epsilon, Param::Background];
}

pub fn run(args: BenchArgs) -> Result<ExitCode> {
    ensure!(args.sensors >= 1 && args.repeat >= 1, "--sensors and --repeat must be at least 1");
    ensure!(!args.sizes.is_empty(), "--sizes needs at least one size");
    if let Some(plot) = &args.plot {
        atomic::check_extension(plot, "svg")?;
    }
    let outputs = [("--json", &args.json), ("--csv", &args.csv), ("--plot", &args.plot)];
    let outputs: Vec<(&str, &std::path::Path)> =
        outputs.iter().filter_map(|(flag, path)| path.as_deref().map(|p| (*flag, p))).collect();
    atomic::check_outputs(&outputs, &args.scene.iter().map(PathBuf::as_path).collect::<Vec<_>>())?;
    if !args.scenes.is_empty() {
        return run_meshes(&args);
    }
    let strategies = if args.strategies.is_empty() { StrategyKind::ALL.to_vec() } else { args.strategies.clone() };
    let size = ImageSize { width: 128, height: 128 };
    let (scene, params) = match &args.scene {
        Some(path) => super::load_scene(path, &args.params.values)?,
        None => (builtin::lightbox(size), RenderParams::resolve(None, &args.params.values)?),
    };
    let estimator = params.estimator;
    let config = BenchConfig {
        scene,
        estimator_kind: params.values.estimator,
        size,
        estimator,
        sizes: args.sizes.clone(),
        strategies,
        sensors: args.sensors,
        repeat: args.repeat,
    };
    super::with_device(args.device, |device| {
        let bar = super::counter::Counter::new((config.sizes.len() * config.repeat) as u64, "rounds");
        let report = bench::run(device, &config, &mut |event| match event {
            BenchEvent::Round { .. } => bar.inc(1),
            BenchEvent::Checked { strategy, result } if super::say::verbose() => bar
                .suspend(|| sensorlight::errln!("self-check {strategy}: max difference {:.2e}", result.max_difference)),
            BenchEvent::Checked { .. } => {}
        })?;
        bar.finish();
        // The files first: a reader of the table that stops early (`| head`) does not lose them.
        let mut files = atomic::Outputs::new();
        if let Some(path) = &args.json {
            files.stage_bytes(path, sensorlight::output::json_text(&report)?.as_bytes())?;
        }
        if let Some(path) = &args.csv {
            files.stage_bytes(path, report.csv().as_bytes())?;
        }
        if let Some(path) = &args.plot {
            files.stage_bytes(path, plot(&report).svg()?.as_bytes())?;
        }
        files.commit()?;
        print_report(&report)
    })
}

/// `--scenes`: the triangle-count axis.
fn run_meshes(args: &BenchArgs) -> Result<ExitCode> {
    ensure!(args.csv.is_none() && args.plot.is_none(), "with --scenes, only --json is written");
    if let Some(json) = &args.json {
        atomic::check_outputs(
            &[("--json", json.as_path())],
            &args.scenes.iter().map(PathBuf::as_path).collect::<Vec<_>>(),
        )?;
    }
    let mut scenes = Vec::new();
    let mut params = None;
    for path in &args.scenes {
        let (scene, p) = super::load_scene(path, &args.params.values)?;
        params.get_or_insert(p);
        scenes.push((path.display().to_string(), scene));
    }
    let params = params.expect("at least one scene");
    let config = MeshBenchConfig {
        scenes,
        estimator_kind: params.values.estimator,
        size: ImageSize { width: 128, height: 128 },
        estimator: params.estimator,
        sizes: args.sizes.clone(),
        strategy: args.strategies.first().copied().unwrap_or(StrategyKind::Layered),
        sensors: args.sensors,
        repeat: args.repeat,
        max_full_detail: args.full_detail_max,
        whole_clusters: args.whole_clusters,
    };
    super::with_device(args.device, |device| {
        let bar = super::counter::Counter::new((config.sizes.len() * config.repeat) as u64, "rounds");
        let report = bench::run_meshes(device, &config, &mut |event| {
            if let BenchEvent::Round { .. } = event {
                bar.inc(1)
            }
        })?;
        bar.finish();
        if let Some(path) = &args.json {
            let mut files = atomic::Outputs::new();
            files.stage_bytes(path, &serde_json::to_vec_pretty(&report)?)?;
            files.commit()?;
        }
        print_mesh_report(&report)
    })
}

fn print_mesh_report(r: &MeshReport) -> Result<()> {
    outln!("device: {} ({})", r.device, r.driver)?;
    outln!("{} sensors, strategy {}, {} timed runs each, interleaved; medians", r.sensor, r.strategy, r.repeat)?;
    outln!(
        "\n| rd | scene | triangles | detail | sensors | ms/sensor | device ms/sensor: culling, maps | triangles \
         drawn/sensor | vs first (full) |"
    )?;
    outln!("|---:|---|---:|---|---:|---:|---|---:|---:|")?;
    let ms = |t: Option<f64>| t.map_or_else(|| "–".into(), |t| format!("{t:.3}"));
    for m in &r.measurements {
        outln!(
            "| {} | {} | {} | {:?} | {} | {:.3} | {}, {} | {} | {:.2}× |",
            m.rd,
            m.scene,
            m.triangles,
            m.detail,
            m.sensors,
            m.ms_per_sensor,
            ms(m.gpu_cull_ms_per_sensor),
            ms(m.gpu_maps_ms_per_sensor),
            match (m.drawn_triangles_per_sensor, m.whole_clusters_per_sensor) {
                (None, _) => "all".into(),
                (Some(t), w) if w > 0.0 => format!("{t:.0} ({w:.2} clusters whole)"),
                (Some(t), _) => format!("{t:.0}"),
            },
            m.vs_first
        )?;
    }
    Ok(())
}

fn print_report(r: &BenchReport) -> Result<()> {
    outln!("device: {} ({})", r.device, r.driver)?;
    outln!(
        "scene: {} ({} triangles); {} sensors, {} per run, {} timed runs each, interleaved; medians [min–max]",
        r.scene,
        r.triangles,
        r.sensor,
        r.sensors,
        r.repeat
    )?;
    for (kind, why) in &r.skipped {
        outln!("not measured: {kind}: {why}")?;
    }
    outln!("\n| rd | strategy | sensors/s [min–max] | Mtexel/s | vs per-sensor | vs raw fill |")?;
    outln!("|---:|---|---:|---:|---:|---:|")?;
    for m in &r.measurements {
        let n = r.sensors as f64;
        let fastest = m.seconds.iter().copied().fold(f64::INFINITY, f64::min);
        let slowest = m.seconds.iter().copied().fold(0.0, f64::max);
        outln!(
            "| {} | {} | {:.0} [{:.0}–{:.0}] | {:.1} | {} | {:.0} % |",
            m.rd,
            m.strategy,
            m.sensors_per_second,
            n / slowest,
            n / fastest,
            m.texels_per_second * 1e-6,
            m.vs_per_sensor.map(|v| format!("{v:.2}×")).unwrap_or_else(|| "–".into()),
            100.0 * m.vs_fill
        )?;
    }
    outln!("\n| rd | raw fill Mtexel/s | reduction alone, sensors/s | reduction share of the best | best |")?;
    outln!("|---:|---:|---:|---:|---|")?;
    for s in &r.sizes {
        outln!(
            "| {} | {:.1} | {:.0} | {:.0} % | {} |",
            s.rd,
            s.fill_texels_per_second * 1e-6,
            1.0 / s.reduction_seconds_per_sensor,
            100.0 * s.reduction_share_of_best,
            s.best
        )?;
    }
    Ok(())
}

fn plot(r: &BenchReport) -> Chart<'static> {
    let mut series: Vec<Series> = Vec::new();
    for m in &r.measurements {
        match series.iter_mut().find(|s| s.name == m.strategy.name()) {
            Some(s) => s.points.push((m.rd as f64, m.sensors_per_second)),
            None => series.push(Series {
                name: m.strategy.name().into(),
                points: vec![(m.rd as f64, m.sensors_per_second)],
                dashed: false,
            }),
        }
    }
    // The fill rate as the sensors per second it would allow.
    let per_sensor_texels = |rd: u32| {
        let layers = if r.sensor == "hemicube" { 3.0 } else { 1.0 };
        layers * (rd as f64).powi(2)
    };
    series.push(Series {
        name: "raw fill (bound)".into(),
        points: r.sizes.iter().map(|s| (s.rd as f64, s.fill_texels_per_second / per_sensor_texels(s.rd))).collect(),
        dashed: true,
    });
    Chart {
        title: "Sensors per second by batching strategy",
        x_label: "sensor map size rd (texels per side)",
        y_label: "sensors / s",
        log_x: true,
        log_y: true,
        series,
    }
}
