//! `sensorlight reference`: the CPU ray-casting reference image of the same estimator.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use sensorlight::output::{atomic, exr::ExrImage, png};
use sensorlight::params::EstimatorParams;
use sensorlight::reference::integrator::{Integrator, REPLICATES};
use sensorlight::scene::Scene;

use super::args::{EstimatorFlags, ImageFlags};

#[derive(Args)]
pub struct ReferenceArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output EXR: RGB = Le + Kd·R, plus radiance.* (R) and std_error.* (its estimated noise).
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    estimator: EstimatorFlags,
    #[command(flatten)]
    image: ImageFlags,
    /// Directions per pixel, a multiple of 4 (powers of two stratify best)
    #[arg(long, default_value_t = 1024)]
    samples: u32,
    /// Seed of the sample scrambling: the same seed writes the same file
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub fn run(args: ReferenceArgs) -> Result<ExitCode> {
    super::check_exr_outputs(&args.output, args.image.write_png(), &[], &[&args.scene])?;
    let scene = Scene::load(&args.scene)?;
    super::check_exr_outputs(&args.output, args.image.write_png(), &[], &scene.input_paths())?;
    super::print_warnings(&scene);
    let params = EstimatorParams::resolve(&scene.render, &args.estimator.overrides())?;
    let size = args.image.size(&scene)?;
    let integrator = Integrator::new(&scene, params, args.samples, args.seed)?;
    eprintln!(
        "reference: {}x{}, {} sensor domain, ε {}, {} directions per pixel ({REPLICATES} × {}), seed {}",
        size.width,
        size.height,
        params.sensor,
        params.epsilon,
        args.samples,
        args.samples / REPLICATES,
        args.seed
    );
    let bar = super::progress_bar(size.height as u64, "rows");
    let start = Instant::now();
    let result = integrator.render(size, &|rows| bar.inc(rows));
    let seconds = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    eprintln!(
        "cast {:.1} M rays in {seconds:.2} s: {:.2} M rays/s on {} threads; noise: mean relative standard error of R {:.3} %",
        result.rays as f64 * 1e-6,
        result.rays as f64 * 1e-6 / seconds,
        rayon::current_num_threads(),
        100.0 * result.relative_noise()
    );
    // Both files or neither: staged, then renamed together.
    let mut files = atomic::Outputs::new();
    ExrImage::new(size.width, size.height)
        .rgb("", &result.image)
        .rgb("radiance", &result.radiance)
        .rgb("std_error", &result.std_error)
        .stage(&mut files, &args.output)?;
    let png_path = args.image.write_png().then(|| args.output.with_extension("png"));
    if let Some(path) = &png_path {
        let exposure = args.image.exposure.unwrap_or(0.0);
        png::stage(&mut files, path, (size.width, size.height), &result.image, exposure)?;
    }
    files.commit()?;
    for path in [Some(&args.output), png_path.as_ref()].into_iter().flatten() {
        eprintln!("wrote {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}
