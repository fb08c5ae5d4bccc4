//! `sensorlight render`: scene in, EXR (+ PNG preview, + stats) out.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context as _, Result};
use clap::Args;
use sensorlight::gpu_types::radiance_state;
use sensorlight::output::{atomic, exr::ExrImage, png};
use sensorlight::params::{Overrides, RenderParams};
use sensorlight::renderer::{RenderOutput, RenderStats, Renderer, default_memory_budget};
use sensorlight::scene::Scene;

use super::args::{EstimatorFlags, ImageFlags, RefinementFlags};

#[derive(Args)]
pub struct RenderArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output EXR (linear radiance), written to a temporary name and renamed.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    estimator: EstimatorFlags,
    #[command(flatten)]
    image: ImageFlags,
    /// rd: sensor map side in texels (even for hemicubes; cost grows with rd²) [default: 256]
    #[arg(long)]
    sensor_size: Option<u32>,
    #[command(flatten)]
    refinement: RefinementFlags,
    /// Also write AOVs into the EXR: radiance.* (R), sensor_mask (1 sensed, 0.5 interpolated), surface_id
    #[arg(long)]
    aovs: bool,
    /// Write the render statistics as JSON to this file (two runs of one command differ only in the measured times)
    #[arg(long)]
    stats_json: Option<PathBuf>,
    /// Memory for one batch of sensor maps, MiB [default: 1/8 of the device's local memory]
    #[arg(long)]
    memory_budget: Option<u64>,
    /// How sensors are batched: auto (the fastest that passes its self-check here), per-sensor, single-cb,
    /// multiview, layered or atlas
    #[arg(long, default_value = "auto")]
    strategy: String,
    /// Device index from `sensorlight devices` [default: the best available]
    #[arg(long)]
    device: Option<usize>,
}

impl RenderArgs {
    fn overrides(&self) -> Overrides {
        self.refinement.overrides(Overrides {
            sensor_size: self.sensor_size,
            exposure: self.image.exposure,
            ..self.estimator.overrides()
        })
    }
}

pub fn run(args: RenderArgs) -> Result<ExitCode> {
    let stats_json: Vec<_> = args.stats_json.iter().map(|p| ("--stats-json", p.as_path())).collect();
    super::check_exr_outputs(&args.output, args.image.write_png(), &stats_json, &[&args.scene])?;
    let scene = Scene::load(&args.scene)?;
    // Again with the mesh and its materials, known now.
    super::check_exr_outputs(&args.output, args.image.write_png(), &stats_json, &scene.input_paths())?;
    super::print_warnings(&scene);
    let params = RenderParams::resolve(&scene.render, &args.overrides())?;
    let size = args.image.size(&scene)?;
    let requested = super::parse_strategy(&args.strategy)?;
    super::with_device(args.device, |device| {
        let budget = args.memory_budget.map(|mib| mib << 20).unwrap_or_else(|| default_memory_budget(device));
        let (sensor, rd) = (params.estimator.sensor, params.sensor_size);
        let strategy = super::choose_strategy(device, sensor, rd, budget, requested)?;
        let mut renderer = Renderer::new(device, &scene, sensor, rd, Some(budget), strategy)?;
        let bar = super::SensorBar(super::progress_bar(0, "sensors"));
        let output = renderer.render(&scene, size, &params, &bar)?;
        bar.0.finish_and_clear();
        print_stats(&output.stats);
        write_outputs(&args, &params, &output)
    })
}

fn print_stats(s: &RenderStats) {
    let rounds: Vec<String> = s.sensors_per_round.iter().map(u64::to_string).collect();
    eprintln!(
        "{} sensors ({}, rd {}, {}) in {} batches of up to {}; per refinement round: {}; {} quads interpolated",
        s.sensors,
        s.sensor,
        s.sensor_size,
        s.strategy,
        s.batches,
        s.batch_size,
        rounds.join(" + "),
        s.interpolated_quads
    );
    eprintln!(
        "{:.2} s total, sensor time {:.4} ms (total / sensors); GPU {:.2} s sensors + {:.2} s other, host {:.2} s; {}",
        s.total_seconds, s.sensor_time_ms, s.gpu_sensor_seconds, s.gpu_other_seconds, s.host_seconds, s.device
    );
}

fn write_outputs(args: &RenderArgs, params: &RenderParams, out: &RenderOutput) -> Result<()> {
    let size = out.size;
    let mut exr = ExrImage::new(size.width, size.height).rgb("", &out.image);
    if args.aovs {
        let mask = out.radiance.iter().map(|r| match r.w {
            w if w == radiance_state::SENSED => 1.0,
            w if w == radiance_state::INTERPOLATED => 0.5,
            _ => 0.0,
        });
        exr = exr
            .rgb("radiance", &out.radiance)
            .scalar("sensor_mask", mask.collect())
            .scalar("surface_id", out.gbuffer.surface.iter().map(|&s| s as f32).collect());
    }
    // Every output or none: all are staged, then renamed together.
    let mut files = atomic::Outputs::new();
    exr.stage(&mut files, &args.output)?;
    let png_path = args.image.write_png().then(|| args.output.with_extension("png"));
    if let Some(path) = &png_path {
        png::stage(&mut files, path, (size.width, size.height), &out.image, params.exposure)?;
    }
    if let Some(path) = &args.stats_json {
        let json = serde_json::to_string_pretty(&out.stats).context("stats to JSON")?;
        files.stage_bytes(path, json.as_bytes())?;
    }
    files.commit()?;
    for path in [Some(&args.output), png_path.as_ref(), args.stats_json.as_ref()].into_iter().flatten() {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
