//! `sensorlight cache`: the radiance cache solved once and written to a file, and `--cache FILE`, which
//! `render` and `view` read instead of solving it: tiles, frames and machines then share one cache.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context as _, Result, bail};
use clap::Args;
use sensorlight::cancel::Cancel;
use sensorlight::gi::file::{CacheFile, Fingerprint};
use sensorlight::output::atomic;
use sensorlight::params::RenderParams;
use sensorlight::renderer::{GiStats, Renderer};
use sensorlight::scene::Scene;
use sensorlight::strategy::Cache;

use super::args::{EngineFlags, LookFlags};
use super::progress::RenderProgress;

#[derive(Args)]
pub struct CacheArgs {
    /// Scene file (TOML), or an OBJ or glTF mesh (as `render` takes it)
    scene: PathBuf,
    /// The cache file to write (all or nothing); `render --cache FILE` and `view --cache FILE` read it
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// `render`'s flags, so that one list serves both; those that act on the camera's pixels alone (the
    /// size, the refinement, the filters, the exposure) change nothing here
    #[command(flatten)]
    look: LookFlags,
    #[command(flatten)]
    engine: EngineFlags,
}

pub fn run(args: CacheArgs) -> Result<ExitCode> {
    atomic::check_outputs(&[("-o", &args.output)], &[&args.scene])?;
    let size = (args.look.image.width, args.look.image.height);
    let (scene, params) = super::load_input(&args.scene, &args.look.overrides(), size, &args.look.lights)?;
    atomic::check_outputs(&[("-o", &args.output)], &scene.input_paths())?;
    if params.estimator.indirect.bounces().is_none() {
        bail!(
            "the light asked for is {}, which needs no radiance cache: a cache is for global illumination \
             (--bounces N ≥ 1 or auto)",
            params.estimator.indirect
        );
    }
    super::warn_all(&sensorlight::gi::albedo_warnings(&scene.mesh));
    let cancel = Cancel::on_signals().context("cannot handle SIGINT and SIGTERM")?;
    super::with_device(args.engine.device, |device| {
        let started = Instant::now();
        let mut strategies = Cache::open_default();
        let mut renderer =
            super::build_renderer(device, (&scene, &params), &args.engine, &mut strategies, &mut |_| ())?;
        cancel.check()?;
        let progress = RenderProgress::new(0, None, cancel.clone());
        let stats = renderer.solve_cache(&params.frame(), &progress)?.context("no radiance cache was solved")?;
        progress.finish();
        cancel.check()?;
        let file = CacheFile {
            fingerprint: Fingerprint::of(&scene, &params),
            stats: serde_json::to_value(&stats)?,
            values: renderer.cache_values()?,
        };
        let bytes = file.to_bytes();
        let mut outputs = atomic::Outputs::new();
        outputs.stage_bytes(&args.output, &bytes)?;
        outputs.commit()?;
        say!(
            "radiance cache: {} entries ({} reached), {} bounces, in {:.2} s → {} ({:.1} MB)",
            stats.entries,
            stats.reached,
            stats.bounces,
            started.elapsed().as_secs_f64(),
            args.output.display(),
            bytes.len() as f64 / 1e6
        );
        Ok(())
    })
}

/// The cache file at `path`, checked against the scene and parameters it is to light: another scene or
/// other settings are refused naming what differs. Read before the renderer is built, so that a wrong file
/// costs nothing.
pub fn read(path: &Path, scene: &Scene, params: &RenderParams) -> Result<CacheFile> {
    let bytes = std::fs::read(path).with_context(|| format!("--cache {}: cannot read it", path.display()))?;
    let file = CacheFile::from_bytes(&bytes).map_err(|e| anyhow::anyhow!("--cache {} {e}", path.display()))?;
    let differences = file.fingerprint.differences(&Fingerprint::of(scene, params));
    if !differences.is_empty() {
        bail!(
            "--cache {} was solved for another scene or other settings; what differs: {}. Solve it again with \
             `sensorlight cache` and this render's scene and flags",
            path.display(),
            differences.join("; ")
        );
    }
    Ok(file)
}

/// Makes `renderer` read `file`'s solution instead of solving the cache.
pub fn apply(renderer: &mut Renderer, file: &CacheFile, params: &RenderParams, path: &Path) -> Result<()> {
    // Statistics the file cannot give (an older layout) are left out, not refused: they only report.
    let stats: GiStats = serde_json::from_value(file.stats.clone()).unwrap_or_default();
    say!(
        "radiance cache: read from {} ({} bounces, {} entries), not solved here",
        path.display(),
        stats.bounces,
        stats.entries
    );
    renderer.use_cache(&file.values, &params.frame(), stats).with_context(|| format!("--cache {}", path.display()))
}
