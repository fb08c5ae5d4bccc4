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
use sensorlight::lightmap::unwrap::{Density, Source, Unwrapped};
use sensorlight::lightmap::{self, Atlas, glb, view};
use sensorlight::output::{atomic, exr::ExrImage, hdr, png};
use sensorlight::scene::bvh::Bvh;
use sensorlight::strategy::Cache;
use sensorlight::vk::Device;

use super::args::{EngineFlags, LookFlags};
use super::progress::RenderProgress;

#[derive(Args)]
#[command(
    after_help = "Every texel's point is sensed as a pixel of `render` would be, after the radiance cache; --aa on \
    (the default) takes a texel over 2 × 2 points of its footprint where its light differs from a neighbour's by \
    more than 10 %. --tile, --dradiance and the filters shape a render's image and do nothing here; --width and \
    --height size the camera the .glb holds and --view's image. A surface shows baseColorFactor × baseColorTexture \
    × the lightmap at TEXCOORD_1 (bilinear), plus its emission: three.js, `material.lightMap` with \
    `lightMap.channel = 1` and `lightMapIntensity = Math.PI` (scripts/threejs/view.js); see the README."
)]
pub struct BakeArgs {
    /// Scene file (TOML), or an OBJ or glTF mesh (framed and lit as `render` frames and lights it)
    scene: PathBuf,
    /// Output: OUT.glb, the scene with its lightmap coordinates (TEXCOORD_1), materials and camera, and
    /// beside it OUT.lightmap.exr, the lightmap (irradiance / π, linear; OUT.lightmap.N.exr per page where
    /// the atlas needs several)
    #[arg(short, long, value_name = "OUT.glb")]
    output: PathBuf,
    /// The atlas's side in texels: the highest density at which every chart fits one page
    #[arg(long, value_name = "S", default_value_t = 512, conflicts_with = "texels_per_unit",
          value_parser = clap::value_parser!(u32).range(16..=16384))]
    size: u32,
    /// Texels per scene unit instead of --size; the page grows to fit
    #[arg(long, value_name = "D", allow_negative_numbers = true)]
    texels_per_unit: Option<f32>,
    /// The lightmap's encoding besides the linear float EXR, always written: rgbm, an 8-bit RGBA PNG (light =
    /// rgb × a × 8, linear) for engines that take 8 bits; hdr, a Radiance RGBE file
    #[arg(long, value_enum, default_value_t = Format::Exr)]
    format: Format,
    /// Also write the view an engine shows of the baked scene from the scene's camera (albedo × lightmap,
    /// bilinear, plus emission) to F.exr and its PNG: to compare with `render`'s image
    #[arg(long, value_name = "F.exr")]
    view: Option<PathBuf>,
    #[command(flatten)]
    pub look: LookFlags,
    #[command(flatten)]
    engine: EngineFlags,
}

/// The lightmap's encodings: the EXR alone, or with another beside it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Format {
    Exr,
    Rgbm,
    Hdr,
}

impl Format {
    /// The other file's extension and how `extras.lightmap.alternate` describes it.
    fn alternate(self) -> Option<(&'static str, serde_json::Value)> {
        match self {
            Format::Exr => None,
            Format::Rgbm => Some(("png", serde_json::json!({ "encoding": "rgbm", "range": lightmap::RGBM_RANGE }))),
            Format::Hdr => Some(("hdr", serde_json::json!({ "encoding": "rgbe" }))),
        }
    }
}

/// The lightmap's file names beside `glb` (OUT.glb → OUT.lightmap.exr, or OUT.lightmap.N.exr per page).
fn lightmap_paths(glb: &Path, pages: u32, extension: &str) -> Vec<PathBuf> {
    let stem = glb.with_extension("");
    let stem = stem.display();
    match pages {
        1 => vec![PathBuf::from(format!("{stem}.lightmap.{extension}"))],
        n => (0..n).map(|k| PathBuf::from(format!("{stem}.lightmap.{k}.{extension}"))).collect(),
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
        let paths = lightmap_paths(&args.output, unwrapped.pages, "exr");
        let alternate = args.format.alternate().map(|(ext, _)| lightmap_paths(&args.output, unwrapped.pages, ext));
        let mut outputs: Vec<(&str, &Path)> = vec![("-o", &args.output)];
        outputs.extend(paths.iter().chain(alternate.iter().flatten()).map(|p| ("the lightmap beside -o", p.as_path())));
        if let Some(v) = &view_outputs {
            outputs.extend(v.paths().map(|p| ("--view", p.as_path())));
        }
        atomic::check_outputs(&outputs, &scene.input_paths())?;
        let from = match &unwrapped.source {
            Source::File => "the file's TEXCOORD_1".to_owned(),
            Source::Unwrapped(why) => {
                if let Some(why) = why {
                    super::warn_all(&[format!("{why}: the lightmap's coordinates are made anew (uvunwrap)")]);
                }
                format!("{} charts", unwrapped.charts)
            }
        };
        say!(
            "lightmap: {} page(s) of {} × {} texels, {from}, {:.3} texels per unit ({:.1} s)",
            unwrapped.pages,
            unwrapped.width,
            unwrapped.height,
            unwrapped.texels_per_unit,
            started.elapsed().as_secs_f64()
        );
        let texels = &layout.texels;
        if texels.backs > 0 {
            say!(
                "lightmap: {} texel(s) hold their surface's back side's light: its front faces into geometry \
                 (the .glb's materials are double-sided)",
                texels.backs
            );
        }
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
        let baked = bake::bake(&mut renderer, (&scene, &bvh), &layout, &params.frame(), &progress)?;
        progress.complete();
        progress.finish();
        cancel.check()?;
        let (n, seconds) = (texels.count(), sensing.elapsed().as_secs_f64());
        say!(
            "baked {n} texels in {seconds:.1} s ({:.0} texels/s; {:.1} s in all); {} taken over their footprint \
             ({} points) where the light changes across them",
            n as f64 / seconds.max(1e-9),
            started.elapsed().as_secs_f64(),
            baked.footprints,
            baked.footprint_points
        );
        let atlas = baked.atlas;
        let files = Files { exr: &paths, alternate: alternate.as_deref() };
        write(&args, (&scene, size), (unwrapped, &atlas, files), (&bvh, view_outputs.as_ref(), &params), &cancel)
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

/// The lightmap's files per page: the EXR's, and those of `--format`'s encoding.
struct Files<'a> {
    exr: &'a [PathBuf],
    alternate: Option<&'a [PathBuf]>,
}

/// The file names of `paths`, as the `.glb` beside them names them.
fn names(paths: &[PathBuf]) -> Vec<String> {
    paths.iter().map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()).collect()
}

/// Writes the `.glb`, its lightmap pages and (with `--view`) the view, all or none.
fn write(
    args: &BakeArgs,
    (scene, size): (&sensorlight::scene::Scene, sensorlight::scene::ImageSize),
    (unwrapped, atlas, files): (&Unwrapped, &Atlas, Files<'_>),
    (bvh, view_outputs, params): (&Bvh, Option<&super::ImageOutputs>, &sensorlight::params::RenderParams),
    cancel: &Cancel,
) -> Result<()> {
    let mut staged = atomic::Outputs::new();
    let (uris, alternate_uris) = (names(files.exr), files.alternate.map(names));
    let alternate = alternate_uris.as_deref().zip(args.format.alternate().map(|(_, e)| e));
    let lightmap = glb::LightmapFile { uris: &uris, alternate };
    let bytes = glb::encode(&scene.mesh, unwrapped, &lightmap, (&scene.camera, size))?;
    staged.stage_bytes(&args.output, &bytes)?;
    let (w, h) = (atlas.width, atlas.height);
    for (page, path) in files.exr.iter().enumerate() {
        ExrImage::new(w, h)
            .attribute("sensorlight.quantity", "irradiance/pi, linear")
            .rgba("", &atlas.page_rgba(page as u32))
            .stage(&mut staged, path)?;
    }
    for (page, path) in files.alternate.into_iter().flatten().enumerate() {
        let texels = atlas.page(page as u32);
        match args.format {
            Format::Rgbm => staged.stage(path, |f| png::encode_rgba8(f, w, h, &lightmap::rgbm(texels)))?,
            Format::Hdr => staged.stage(path, |f| hdr::encode(f, w, h, texels))?,
            Format::Exr => {}
        }
    }
    let mut written: Vec<&Path> = vec![&args.output];
    written.extend(files.exr.iter().chain(files.alternate.into_iter().flatten()).map(PathBuf::as_path));
    if let Some(outputs) = view_outputs {
        let background = params.estimator.background;
        let shown = view::view(scene, bvh, (unwrapped, atlas), size, background);
        let image: Vec<Vec4> = shown.iter().map(|s| s.colour).collect();
        if let Some(path) = &outputs.exr {
            ExrImage::new(size.width, size.height).rgba("", &image).stage(&mut staged, path)?;
        }
        if let Some(path) = &outputs.png {
            png::stage(&mut staged, path, (size.width, size.height), &image, params.values.exposure)?;
        }
        written.extend(outputs.paths().map(PathBuf::as_path));
    }
    cancel.check()?;
    staged.commit()?;
    for path in written {
        say!("wrote {}", path.display());
    }
    Ok(())
}
