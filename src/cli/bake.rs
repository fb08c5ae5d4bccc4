//! `sensorlight bake`: a scene in, a glTF binary with a lightmap on every surface out (`lightmap`,
//! docs/DESIGN.md §14).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context as _, Result, bail, ensure};
use clap::Args;
use glam::Vec4;
use sensorlight::bake::{self, Layout};
use sensorlight::cancel::Cancel;
use sensorlight::lightmap::unwrap::{Density, Unwrapped};
use sensorlight::lightmap::{Atlas, glb, view};
use sensorlight::output::{atomic, exr::ExrImage, png};
use sensorlight::scene::bvh::Bvh;
use sensorlight::strategy::Cache;
use sensorlight::vk::Device;

use super::args::{EngineFlags, LookFlags};
use super::progress::RenderProgress;

#[derive(Args)]
pub struct BakeArgs {
    /// Scene file (TOML), or an OBJ or glTF mesh (framed and lit as `render` frames and lights it)
    scene: PathBuf,
    /// Output: OUT.glb, the scene with its lightmap coordinates (TEXCOORD_1), materials and camera, and
    /// beside it OUT.lightmap.exr, the lightmap (irradiance / π, linear; OUT.lightmap.N.exr per page where
    /// the atlas needs several)
    #[arg(short, long, value_name = "OUT.glb")]
    output: PathBuf,
    /// The atlas's side in texels: the highest density at which every chart fits one page
    #[arg(long, value_name = "S", default_value_t = 256, conflicts_with = "texels_per_unit",
          value_parser = clap::value_parser!(u32).range(16..=16384))]
    size: u32,
    /// Texels per scene unit instead of --size; the page grows to fit
    #[arg(long, value_name = "D", allow_negative_numbers = true)]
    texels_per_unit: Option<f32>,
    /// Also write the view an engine shows of the baked scene from the scene's camera (albedo × lightmap,
    /// bilinear, plus emission) to F.exr and its PNG: to compare with `render`'s image
    #[arg(long, value_name = "F.exr")]
    view: Option<PathBuf>,
    #[command(flatten)]
    pub look: LookFlags,
    #[command(flatten)]
    engine: EngineFlags,
}

/// The lightmap's file names beside `glb` (OUT.glb → OUT.lightmap.exr, or OUT.lightmap.N.exr per page).
fn lightmap_paths(glb: &Path, pages: u32) -> Vec<PathBuf> {
    let stem = glb.with_extension("");
    let stem = stem.display();
    match pages {
        1 => vec![PathBuf::from(format!("{stem}.lightmap.exr"))],
        n => (0..n).map(|k| PathBuf::from(format!("{stem}.lightmap.{k}.exr"))).collect(),
    }
}

pub fn run(args: BakeArgs) -> Result<ExitCode> {
    let extension = args.output.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    ensure!(
        extension.as_deref() == Some("glb"),
        "{}: expected a .glb file name (the baked scene, a glTF binary; its lightmap is written beside it)",
        args.output.display()
    );
    let density = match args.texels_per_unit {
        Some(d) if !(d.is_finite() && d > 0.0) => bail!("--texels-per-unit must be a positive number, got {d}"),
        Some(d) => Density::PerUnit(d),
        None => Density::Side(args.size),
    };
    let view_outputs = args.view.as_deref().map(|p| super::ImageOutputs::new(p, true)).transpose()?;
    let size = (args.look.image.width, args.look.image.height);
    let (scene, params) = super::load_input(&args.scene, &args.look.overrides(), size, &args.look.lights)?;
    let size = args.look.image.size(&scene)?;
    let cancel = Cancel::on_signals().context("cannot handle SIGINT and SIGTERM")?;
    super::with_device(args.engine.device, |device| {
        let started = Instant::now();
        let bvh = Bvh::build(&scene.mesh.triangles);
        let layout = Layout::new(&scene, &bvh, density, device.adapter.limits.max_image_dimension_2d)?;
        let unwrapped = &layout.unwrapped;
        check_memory(device, unwrapped)?;
        let paths = lightmap_paths(&args.output, unwrapped.pages);
        let mut outputs: Vec<(&str, &Path)> = vec![("-o", &args.output)];
        outputs.extend(paths.iter().map(|p| ("the lightmap beside -o", p.as_path())));
        if let Some(v) = &view_outputs {
            outputs.extend(v.paths().map(|p| ("--view", p.as_path())));
        }
        atomic::check_outputs(&outputs, &scene.input_paths())?;
        say!(
            "lightmap: {} page(s) of {} × {} texels, {} charts, {:.3} texels per unit ({:.1} s)",
            unwrapped.pages,
            unwrapped.width,
            unwrapped.height,
            unwrapped.charts,
            unwrapped.texels_per_unit,
            started.elapsed().as_secs_f64()
        );
        let texels = &layout.texels;
        if texels.moved + texels.buried > 0 {
            say!(
                "lightmap: {} texel(s) inside geometry moved to the open part of their footprint; {} wholly \
                 inside, filled from their neighbours",
                texels.moved,
                texels.buried
            );
        }
        let progress = RenderProgress::for_texels(texels.count() as u64, cancel.clone());
        let mut cache = Cache::open_default();
        let mut renderer = super::build_renderer(device, (&scene, &params), &args.engine, &mut cache, &mut |_| ())?;
        let sensing = Instant::now();
        let atlas = bake::bake(&mut renderer, &scene, &layout, &params.frame(), &progress)?;
        progress.complete();
        progress.finish();
        cancel.check()?;
        let (n, seconds) = (texels.count(), sensing.elapsed().as_secs_f64());
        say!(
            "baked {n} texels in {seconds:.1} s ({:.0} texels/s; {:.1} s in all)",
            n as f64 / seconds.max(1e-9),
            started.elapsed().as_secs_f64()
        );
        write(&args, (&scene, size), (unwrapped, &atlas, &paths), (&bvh, view_outputs.as_ref(), &params), &cancel)
    })
}

/// Refuses an atlas an engine could not hold beside the scene: more than an eighth of the device's memory
/// as RGBA float.
fn check_memory(device: &Device, unwrapped: &Unwrapped) -> Result<()> {
    let (w, h) = (unwrapped.width, unwrapped.height);
    let bytes = w as u64 * h as u64 * unwrapped.pages as u64 * 16;
    let limit = device.adapter.device_local_bytes / 8;
    ensure!(
        bytes <= limit,
        "the lightmap would need {} MiB as RGBA float ({} page(s) of {w} × {h}), more than an eighth of this \
         device's memory ({} MiB); give a smaller --texels-per-unit or --size",
        bytes >> 20,
        unwrapped.pages,
        limit >> 20
    );
    Ok(())
}

/// Writes the `.glb`, its lightmap pages and (with `--view`) the view, all or none.
fn write(
    args: &BakeArgs,
    (scene, size): (&sensorlight::scene::Scene, sensorlight::scene::ImageSize),
    (unwrapped, atlas, paths): (&Unwrapped, &Atlas, &[PathBuf]),
    (bvh, view_outputs, params): (&Bvh, Option<&super::ImageOutputs>, &sensorlight::params::RenderParams),
    cancel: &Cancel,
) -> Result<()> {
    let mut files = atomic::Outputs::new();
    let uris: Vec<String> =
        paths.iter().map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()).collect();
    let bytes = glb::encode(&scene.mesh, unwrapped, &glb::LightmapFile { uris: &uris }, (&scene.camera, size))?;
    files.stage_bytes(&args.output, &bytes)?;
    for (page, path) in paths.iter().enumerate() {
        ExrImage::new(atlas.width, atlas.height)
            .attribute("sensorlight.quantity", "irradiance/pi, linear")
            .rgba("", &atlas.page_rgba(page as u32))
            .stage(&mut files, path)?;
    }
    let mut written: Vec<&Path> = vec![&args.output];
    written.extend(paths.iter().map(PathBuf::as_path));
    if let Some(outputs) = view_outputs {
        let background = params.estimator.background;
        let shown = view::view(scene, bvh, (unwrapped, atlas), size, background);
        let image: Vec<Vec4> = shown.iter().map(|s| s.colour).collect();
        if let Some(path) = &outputs.exr {
            ExrImage::new(size.width, size.height).rgba("", &image).stage(&mut files, path)?;
        }
        if let Some(path) = &outputs.png {
            png::stage(&mut files, path, (size.width, size.height), &image, params.values.exposure)?;
        }
        written.extend(outputs.paths().map(PathBuf::as_path));
    }
    cancel.check()?;
    files.commit()?;
    for path in written {
        say!("wrote {}", path.display());
    }
    Ok(())
}
