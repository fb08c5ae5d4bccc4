//! `sensorlight compare`: how far an image is from a reference image.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;
use sensorlight::metrics::compare::compare_files;
use sensorlight::outln;
use sensorlight::output::atomic;

#[derive(Args)]
#[command(after_help = "The headline is the per-pixel relative RMSE of luminance over the lit pixels of the \
    reference (luminance above 1 % of its mean) over the whole image, nothing masked; the second figure is the \
    interior's: silhouettes masked where a surface_id channel exists, emitters where an emission layer does, \
    and the background. Images holding NaN or infinite values, or of different sizes, are errors.")]
pub struct CompareArgs {
    /// The image to judge (EXR).
    image: PathBuf,
    /// The reference (EXR), e.g. from `sensorlight reference`.
    reference: PathBuf,
    /// Channel group to compare: empty for the main R, G, B, or e.g. `radiance`
    #[arg(long, default_value = "")]
    layer: String,
    /// Also write the figures as JSON to this file
    #[arg(long)]
    json: Option<PathBuf>,
}

pub fn run(args: CompareArgs) -> Result<ExitCode> {
    if let Some(json) = &args.json {
        atomic::check_outputs(&[("--json", json)], &[&args.image, &args.reference])?;
    }
    let a = compare_files(&args.image, &args.reference, &args.layer)?;
    if let Some(json) = &args.json {
        atomic::write_bytes(json, &a.to_json(&args.image, &args.reference, &args.layer)?)?;
    }
    for line in a.summary() {
        outln!("{line}")?;
    }
    Ok(ExitCode::SUCCESS)
}
