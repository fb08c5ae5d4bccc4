//! `sensorlight reference`: the CPU ray-casting reference image of the same estimator.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context as _, Result};
use clap::Args;
use sensorlight::cancel::Cancel;
use sensorlight::output::{atomic, exr::ExrImage, png};
use sensorlight::params::Param;
use sensorlight::params::flags::{FlagSet, ParamFlags};
use sensorlight::reference::integrator::{Integrator, REPLICATES};

use super::args::{ImageFlags, LightFlags};

#[derive(Args)]
pub struct ReferenceArgs {
    /// Scene file (TOML), or an OBJ mesh (a camera framing it, as `render` does)
    scene: PathBuf,
    /// Output EXR: RGB = Le + Kd·R, plus radiance.* (R), and the estimated noise of each: std_error.* and
    /// radiance_std_error.* (what `compare` reports as the reference's noise); the PNG beside it unless
    /// --no-png. F.png writes the PNG alone
    #[arg(short, long, value_name = "F.exr|F.png")]
    output: PathBuf,
    #[command(flatten)]
    params: ParamFlags<ReferenceParams>,
    #[command(flatten)]
    image: ImageFlags,
    #[command(flatten)]
    lights: LightFlags,
    /// Samples per pixel, a multiple of 4 (powers of two stratify best). Each is one cosine-weighted
    /// direction plus, if the scene has emitters, one point on an emitter, combined by multiple importance
    /// sampling (up to 2 rays). With global illumination (--bounces other than 0) the direction is a path:
    /// at each surface it meets, a point on an emitter and a cosine direction that goes on (up to 2 rays a
    /// vertex), until N surfaces have reflected it (--bounces N) or Russian roulette (after 3 bounces) ends it
    #[arg(long, default_value_t = 1024)]
    samples: u32,
    /// Seed of the sample scrambling: the same seed writes the same file
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// What the reference takes of the parameters: what a sensor sees and the image; the rest (refinement,
/// filters, the cache) is the renderer's.
pub enum ReferenceParams {}

impl FlagSet for ReferenceParams {
    const PARAMS: &'static [Param] =
        &[Param::Sensor, Param::Fov, Param::Epsilon, Param::Background, Param::Bounces, Param::Exposure, Param::Aa];
}

pub fn run(args: ReferenceArgs) -> Result<ExitCode> {
    let cancel = Cancel::on_signals().context("cannot handle SIGINT and SIGTERM")?;
    let outputs = super::ImageOutputs::new(&args.output, args.image.write_png())?;
    outputs.check(&[], &[&args.scene])?;
    let flags = args.params.values.clone();
    let (scene, resolved) =
        super::load_input(&args.scene, &flags, (args.image.width, args.image.height), &args.lights)?;
    outputs.check(&[], &scene.input_paths())?;
    let params = resolved.estimator;
    let size = args.image.size(&scene)?;
    let integrator = Integrator::new(&scene, params, args.samples, args.seed)?;
    super::warn_all(&integrator.warnings());
    let strategies = match (params.indirect.bounces().is_some(), integrator.emitters()) {
        (false, 0) => "a direction each: the scene has no emitters".to_string(),
        (false, n) => format!("a direction + a point on one of {n} emitter triangles each"),
        (true, 0) => "a path of cosine directions each: the scene has no emitters".to_string(),
        (true, n) => format!(
            "a path (a direction; at each surface it meets, a light point and the next direction) + a point on one \
             of {n} emitter triangles each"
        ),
    };
    let strategies = match &scene.sky {
        Some(sky) if sky.can_sample() => format!("{strategies}, + a direction drawn from the sky map by its luminance"),
        _ => strategies,
    };
    say!(
        "reference: {}x{}, {}, {} sensor domain, {}, {} samples per pixel ({REPLICATES} × {}; {strategies}), seed {}",
        size.width,
        size.height,
        match resolved.values.aa {
            sensorlight::params::Antialiasing::On => "each pixel over its square (each sample at its own point)",
            sensorlight::params::Antialiasing::Off => "each pixel at its centre (--aa off)",
        },
        params.sensor,
        params.indirect,
        args.samples,
        args.samples / REPLICATES,
        args.seed
    );
    let bar = super::counter::Counter::new(size.height as u64, "rows");
    let start = Instant::now();
    let result = integrator.render_until(size, resolved.values.aa, &|rows| bar.inc(rows), &cancel);
    bar.finish();
    let result = result?;
    let seconds = start.elapsed().as_secs_f64();
    if let Some(at) = result.image.iter().position(|v| !v.is_finite()) {
        anyhow::bail!(
            "pixel ({}, {}) of the reference is not finite ({}): the light (Ke, --background) summed over \
             samples and bounces exceeds 32-bit floats; lower it",
            at % size.width as usize,
            at / size.width as usize,
            result.image[at]
        );
    }
    say!(
        "cast {:.1} M rays in {seconds:.2} s: {:.2} M rays/s on {} threads; noise: mean relative standard error of R {:.3} %",
        result.rays as f64 * 1e-6,
        result.rays as f64 * 1e-6 / seconds,
        rayon::current_num_threads(),
        100.0 * result.relative_noise()
    );
    // Both files or neither: staged, then renamed together.
    let mut files = atomic::Outputs::new();
    if let Some(path) = &outputs.exr {
        let exr = ExrImage::new(size.width, size.height).rgba("", &result.image);
        super::gbuffer_aovs(exr, &result.gbuffer, scene.camera.eye)
            .rgb("radiance", &result.radiance)
            .rgb("std_error", &result.image_std_error)
            .rgb("radiance_std_error", &result.std_error)
            .stage(&mut files, path)?;
    }
    if let Some(path) = &outputs.png {
        let (exposure, auto) = super::png_exposure(&resolved, &args.scene, &result.image, &result.gbuffer);
        if let Some(text) = auto {
            say!("{text}");
        }
        png::stage(&mut files, path, (size.width, size.height), &result.image, exposure)?;
    }
    files.commit()?;
    for path in outputs.paths() {
        say!("wrote {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}
