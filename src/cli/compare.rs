//! `sensorlight compare`: how far an image is from a reference image.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;
use sensorlight::outln;
use sensorlight::output::compare::compare_files;

#[derive(Args)]
pub struct CompareArgs {
    /// The image to judge (EXR).
    image: PathBuf,
    /// The reference (EXR), e.g. from `sensorlight reference`.
    reference: PathBuf,
    /// Channel group to compare: empty for the main R, G, B, or e.g. `radiance`
    #[arg(long, default_value = "")]
    layer: String,
}

pub fn run(args: CompareArgs) -> Result<ExitCode> {
    let a = compare_files(&args.image, &args.reference, &args.layer)?;
    outln!(
        "relative RMSE {:.4}, relative mean absolute error {:.4}, relative bias {:+.4}, over {} pixels",
        a.relative_rmse,
        a.relative_mean_abs,
        a.relative_bias,
        a.pixels
    )?;
    Ok(ExitCode::SUCCESS)
}
