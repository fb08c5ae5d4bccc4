//! `sensorlight render`: scene in, EXR out.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;
use glam::Vec4;
use sensorlight::gpu_scene::GpuScene;
use sensorlight::output::exr::ExrImage;
use sensorlight::passes::gbuffer::{self, GBufferPass};
use sensorlight::scene::{ImageSize, Scene};

#[derive(Args)]
#[command(long_about = "Render a scene to an EXR.\n\n\
    Until the sensor pipeline lands this writes the G-buffer AOVs: RGB = emission + albedo (unlit), and the \
    channel groups albedo.*, normal.*, position.* and surface_id.")]
pub struct RenderArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output EXR file (written to a temporary name, then renamed).
    #[arg(short, long)]
    output: PathBuf,
    /// Image width in pixels (default: the scene's [image] width).
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels (default: the scene's [image] height).
    #[arg(long)]
    height: Option<u32>,
    /// Device index from `sensorlight devices` (default: the best available).
    #[arg(long)]
    device: Option<usize>,
}

pub fn run(args: RenderArgs) -> Result<ExitCode> {
    let scene = Scene::load(&args.scene)?;
    super::print_warnings(&scene);
    let size =
        ImageSize { width: args.width.unwrap_or(scene.image.width), height: args.height.unwrap_or(scene.image.height) };
    anyhow::ensure!(size.width >= 1 && size.height >= 1, "--width and --height must be at least 1");
    super::with_device(args.device, |device| {
        let gpu_scene = GpuScene::upload(device, &scene)?;
        let pass = GBufferPass::new(device, &gpu_scene)?;
        let near = gbuffer::NEAR * scene.mesh.scale();
        let g = pass.render(device, &gpu_scene, &scene.camera, size, near)?.read_back(device)?;
        let unlit: Vec<Vec4> =
            g.albedo.iter().zip(&g.emission).map(|(a, e)| (a.truncate() + e.truncate()).extend(1.0)).collect();
        ExrImage::new(size.width, size.height)
            .rgb("", &unlit)
            .rgb("albedo", &g.albedo)
            .rgb("normal", &g.normal)
            .rgb("position", &g.position)
            .scalar("surface_id", g.surface.iter().map(|&s| s as f32).collect())
            .write(&args.output)?;
        eprintln!("wrote {}", args.output.display());
        let png_path = args.output.with_extension("png");
        sensorlight::output::png::write(&png_path, size.width, size.height, &unlit, 0.0)?;
        eprintln!("wrote {}", png_path.display());
        Ok(())
    })
}
