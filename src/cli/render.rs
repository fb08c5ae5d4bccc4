//! `sensorlight render`: scene in, EXR (+ PNG preview, + stats) out.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context as _, Result, ensure};
use clap::Args;
use sensorlight::cancel::Cancel;
use sensorlight::gpu_types::radiance_state;
use sensorlight::output::{atomic, exr::ExrImage, png};
use sensorlight::params::{Antialiasing, FrameParams, RenderParams};
use sensorlight::renderer::{FINE_FACTOR, LaterBounces, RenderOutput, RenderStats};
use sensorlight::scene::Scene;
use sensorlight::strategy::{Cache, Event};

use super::args::{EngineFlags, LookFlags};
use super::progress::{Preview, RenderProgress};
use super::say;

#[derive(Args)]
pub struct RenderArgs {
    /// Scene file (TOML), or an OBJ mesh: then a camera frames it, the image is 256×256 unless --width and
    /// --height say otherwise, and a mesh that emits no light is lit by a white sky
    scene: PathBuf,
    /// Output: F.exr, the EXR of linear radiance, with the tone-mapped F.png beside it (unless --no-png); or
    /// F.png, the PNG alone. Written to a temporary name and renamed
    #[arg(short, long, value_name = "F.exr|F.png")]
    output: PathBuf,
    #[command(flatten)]
    pub look: LookFlags,
    /// Also write AOVs into the EXR (an .exr output only): radiance.* (R; a supersampled pixel's, the mean
    /// over its samples on a surface), sensor_mask (1 sensed, 0.5 interpolated), supersampled (1 where the
    /// pixel took sub-pixel samples), surface_id, emission.*, and a denoiser's: albedo.* (Kd), normal.X/Y/Z
    /// (unit, world space), depth.Z (distance from the eye), each of what the pixel's centre sees (of a
    /// supersampled pixel whose samples mostly show another surface: of that surface)
    #[arg(long)]
    aovs: bool,
    /// Write the render statistics as JSON to this file (two runs of one command differ only in the measured times)
    #[arg(long)]
    stats_json: Option<PathBuf>,
    #[command(flatten)]
    engine: EngineFlags,
    /// Read the radiance cache from this file (`sensorlight cache`) instead of solving it; refused, naming
    /// what differs, where it was solved for another scene or other settings
    #[arg(long, value_name = "FILE")]
    cache: Option<PathBuf>,
    /// Render only tile I of N (from 1; --tile is the refinement's grid step): the band of rows
    /// (I − 1)·H/N .. I·H/N, every AOV included, into an EXR whose data window says where it lies (no PNG);
    /// `sensorlight assemble` joins the N tiles into the image this render would write without
    /// --image-tile, bit for bit (give every tile the same flags)
    #[arg(long, value_name = "I/N", conflicts_with = "frames")]
    image_tile: Option<super::tiles::TileSpec>,
    /// Render frame K of the scene file's camera path ([path]: the camera at time K / fps), to OUT.####.exr
    /// (OUT.0007.exr for frame 7) and its PNG
    #[arg(long, value_name = "K", conflicts_with = "frames")]
    frame: Option<u32>,
    /// Render frames A to B (both included) of the camera path, each to OUT.####.exr and its PNG; one
    /// radiance cache serves them all
    #[arg(long, value_name = "A..B")]
    frames: Option<super::frames::FrameRange>,
    /// Every N refinement rounds, write the image so far (unfiltered) to OUT.preview.png; it is removed once
    /// the render ends
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    preview_every: Option<u32>,
    /// Also write the scene as rendered (for a mesh: its automatic camera) as a TOML scene file to edit
    #[arg(long, value_name = "SCENE.toml")]
    write_scene: Option<PathBuf>,
}

/// Where `--preview-every` writes: beside the EXR, never one of the final outputs, so that their all-or-none
/// staging is untouched (a preview is written whole, by its own rename, each time).
fn preview_path(output: &Path) -> PathBuf {
    output.with_extension("preview.png")
}

pub fn run(args: RenderArgs) -> Result<ExitCode> {
    let preview = args.preview_every.map(|_| preview_path(&args.output));
    let mut extra: Vec<(&str, &Path)> = Vec::new();
    extra.extend(args.stats_json.as_deref().map(|p| ("--stats-json", p)));
    extra.extend(args.write_scene.as_deref().map(|p| ("--write-scene", p)));
    extra.extend(preview.as_deref().map(|p| ("the --preview-every preview", p)));
    if let Some(path) = &args.write_scene {
        atomic::check_extension(path, "toml")?;
    }
    // A tile's PNG would need the whole image's exposure: `assemble` writes it.
    ensure!(
        args.image_tile.is_none() || super::OutputKind::of(&args.output)? == super::OutputKind::Exr,
        "--image-tile writes an EXR (its PNG is `assemble`'s), and -o {} asks for a PNG alone; name an .exr output",
        args.output.display()
    );
    let png = args.look.image.write_png() && args.image_tile.is_none();
    let numbers: Vec<Option<u32>> = match (args.frame, args.frames) {
        (Some(k), _) => vec![Some(k)],
        (None, Some(range)) => (range.first..=range.last).map(Some).collect(),
        (None, None) => vec![None],
    };
    let jobs = (numbers.iter())
        .map(|&k| {
            Ok((
                k,
                super::ImageOutputs::new(
                    &k.map_or_else(|| args.output.clone(), |k| super::frames::numbered(&args.output, k)),
                    png,
                )?,
            ))
        })
        .collect::<Result<Vec<_>>>()?;
    let outputs = &jobs[0].1;

    ensure!(
        !args.aovs || outputs.exr.is_some(),
        "--aovs writes its layers into the EXR, and -o {} asks for a PNG alone; name an .exr output (its PNG is \
         written beside it)",
        args.output.display()
    );
    let mut inputs = vec![args.scene.as_path()];
    inputs.extend(args.cache.as_deref());
    jobs.iter().try_for_each(|(_, outputs)| outputs.check(&extra, &inputs))?;
    let size = (args.look.image.width, args.look.image.height);
    let (mut scene, params) = super::load_input(&args.scene, &args.look.overrides(), size, &args.look.lights)?;
    let path = super::frames::path_of(&scene, &numbers)?;
    let cache_file = args.cache.as_deref().map(|path| super::cache::read(path, &scene, &params)).transpose()?;
    if params.estimator.indirect.bounces().is_some() {
        super::warn_all(&sensorlight::gi::albedo_warnings(&scene.mesh));
    }
    // Again with the mesh and its materials, known now.
    let mut inputs = scene.input_paths();
    inputs.extend(args.cache.as_deref());
    jobs.iter().try_for_each(|(_, outputs)| outputs.check(&extra, &inputs))?;
    let size = args.look.image.size(&scene)?;
    if let Some(tile) = args.image_tile {
        tile.rows(size)?;
    }
    // From here on Ctrl-C (or SIGTERM) stops the render between batches, and the way out removes the preview
    // and every staged output.
    let cancel = Cancel::on_signals().context("cannot handle SIGINT and SIGTERM")?;
    super::with_device(args.engine.device, |device| {
        let started = Instant::now();
        let preview = preview.map(|path| Preview {
            every: args.preview_every.unwrap_or(1),
            path,
            exposure: params.values.exposure,
        });
        let progress = RenderProgress::new(size.width as u64 * size.height as u64, preview, cancel.clone());
        let _remove_preview = RemoveOnDrop(preview_path(&args.output), args.preview_every.is_some());
        let mut cache = Cache::open_default();
        let mut measured = Vec::new();
        let mut report = |event: Event| {
            if let (true, Some(text)) = (say::verbose(), super::strategy_event_text(&event)) {
                progress.say(&text);
            }
            if let Event::Measured { per_sensor, .. } = event {
                measured = per_sensor;
            }
        };
        let mut renderer = super::build_renderer(device, (&scene, &params), &args.engine, &mut cache, &mut report)?;
        if let (Some(file), Some(path)) = (&cache_file, &args.cache) {
            super::cache::apply(&mut renderer, file, &params, path)?;
        }
        cancel.check()?;
        if let Some(&(_, t)) = measured.iter().find(|(kind, _)| *kind == renderer.strategy()) {
            progress.probe_measured(t);
        }
        if say::verbose() {
            progress.say(&format!("strategy: {} ({})", renderer.strategy(), renderer.choice().reason));
        }
        if let Some(probe) = renderer.detail_probe() {
            progress.say(&detail_line(probe, scene.mesh.triangles.len()));
        }
        let frame = match args.image_tile {
            Some(tile) => FrameParams { region: Some(tile.region(size)?), ..params.frame() },
            None => params.frame(),
        };
        // The frames of a path share the renderer and its radiance cache (it does not depend on the camera).
        renderer.keep_cache();
        let mut first = Some((progress, started));
        for (number, outputs) in &jobs {
            let (progress, started) = first.take().unwrap_or_else(|| {
                (RenderProgress::new(size.width as u64 * size.height as u64, None, cancel.clone()), Instant::now())
            });
            if let (Some(k), Some(path)) = (number, &path) {
                let camera = path.camera(*k)?;
                renderer.set_camera(camera);
                scene.camera = camera;
                progress.say(&format!("frame {k}: camera at {}", camera.eye));
            }
            let output = renderer.render(size, &frame, &progress)?;
            progress.complete();
            progress.finish();
            cancel.check()?;
            print_stats(&output.stats, started.elapsed());
            if say::normal()
                && let Some(warning) = black_image_warning(&output.image, &scene, &params, &args.scene)
            {
                sensorlight::errln!("warning: {warning}");
            }
            write_outputs(&args, (outputs, *number), (&scene, &params), &output, &cancel)?;
        }
        Ok(())
    })
}

/// A pixel is lit above this fraction of the scene's brightest light (its brightest `Ke` component or the
/// background's): below it, rounding noise, not light.
const LIT: f32 = 1e-6;

/// Why the image is black and what to do, if no pixel of `image` is lit (see [`LIT`]): a render that exits
/// 0 with a black image and says nothing leaves its user guessing (a camera outside a closed room).
fn black_image_warning(image: &[glam::Vec4], scene: &Scene, params: &RenderParams, input: &Path) -> Option<String> {
    let sky = scene.sky.as_ref().map_or(0.0, |s| s.mean().max_element());
    let light = scene.mesh.brightest_emission().max(params.estimator.background.max_element()).max(sky);
    if light > 0.0 && image.iter().any(|p| p.truncate().max_element() > LIT * light) {
        return None;
    }
    let c = &scene.camera;
    let target = c.eye + c.forward * (scene.mesh.bounds.center() - c.eye).length().max(0.1 * scene.mesh.scale());
    let why = if light > 0.0 { "no lit surface is in view" } else { "nothing emits light and the background is black" };
    let fix = match sensorlight::scene::FileKind::of(input) {
        sensorlight::scene::FileKind::ObjMesh | sensorlight::scene::FileKind::GltfMesh => {
            "write the scene with --write-scene, move the camera (or set [render] background) and render the scene \
             file"
        }
        _ => "move the camera in the scene file (or light the scene: Ke in the MTL, --background)",
    };
    Some(format!("the image is black: {why} (the camera is at {}, looking at {target}); {fix}", c.eye))
}

/// Removes the preview file when the render ends, whichever way: it showed a render in progress.
struct RemoveOnDrop(PathBuf, bool);

impl Drop for RemoveOnDrop {
    fn drop(&mut self) {
        if self.1 {
            let _ = std::fs::remove_file(&self.0);
        }
    }
}

/// How the sensor maps draw the scene, where the renderer measured it.
fn detail_line(probe: &sensorlight::renderer::detail::DetailProbe, triangles: usize) -> String {
    let way = match probe.detail {
        sensorlight::renderer::Detail::Clusters => "from its clusters",
        _ => "at full detail",
    };
    match (probe.times, probe.difference) {
        (Some((full, clusters)), Some(difference)) => format!(
            "detail: the sensor maps draw the {triangles}-triangle mesh {way} (measured here: {:.3} ms a sensor at \
             full detail, {:.3} from clusters; R within {difference:.1e} of full detail's)",
            full.as_secs_f64() * 1e3,
            clusters.as_secs_f64() * 1e3
        ),
        _ => format!("detail: the sensor maps draw the {triangles}-triangle mesh {way} (as measured before here)"),
    }
}

/// One line by default; with `-v` the counts and the split of the time.
fn print_stats(s: &RenderStats, wall: Duration) {
    if !say::normal() {
        return;
    }
    // No sensor at all where no pixel shows a surface: no time per sensor to give.
    let sensors = match s.sensors {
        0 => "no sensors (no pixel shows a surface)".to_owned(),
        1 => format!("1 sensor, sensor time {:.4} ms", s.sensor_time_ms),
        n => format!("{n} sensors, sensor time {:.4} ms", s.sensor_time_ms),
    };
    sensorlight::errln!(
        "rendered in {:.2} s (strategy choice and setup {:.2} s + render {:.2} s): {sensors}; strategy {}, {}",
        wall.as_secs_f64(),
        s.build_seconds,
        s.total_seconds,
        s.strategy,
        s.device
    );
    match s.aa {
        Antialiasing::On => sensorlight::errln!(
            "antialiasing: {} pixel(s) ({:.1} %) not uniform over their square took {} sub-pixel samples each \
             ({:.2} s on the host; --aa off: pixel centres only)",
            s.supersampled_pixels,
            100.0 * s.supersampled_share,
            sensorlight::supersample::SAMPLES,
            s.times.host_supersample_seconds
        ),
        Antialiasing::Off => sensorlight::errln!("antialiasing off: each pixel is its centre"),
    }
    if let Some(g) = &s.gi {
        let change = g.last_change.map_or(String::new(), |c| format!(", last change {:.2} %", 100.0 * c));
        let tail = g.ratio.map_or(String::new(), |r| {
            format!(", the rest extrapolated (ratio {r:.3}: {:.1} % of the light)", 100.0 * g.tail_share)
        });
        let later = match g.later {
            LaterBounces::Transport { nonzeros, bytes } => format!(
                "the others as products with what they see of each other ({nonzeros} weights, {:.1} MiB)",
                bytes as f64 / (1 << 20) as f64
            ),
            LaterBounces::Sensed { budget } => format!(
                "the others sensed at rd {} (what they see of each other would need over {:.0} MiB)",
                g.sensor_size,
                budget as f64 / (1 << 20) as f64
            ),
        };
        sensorlight::errln!(
            "global illumination: {} bounce(s) in {:.2} s{change}{tail}: the first sensed the {} of {} cache entries \
             light reaches ({} spread sensors), {later}; cache {} cells along the longest side ({:.3} each), {} \
             keys, {:.1} KiB",
            g.bounces,
            g.seconds.0 + g.seconds.1,
            g.reached,
            g.entries,
            g.spread_sensors,
            g.resolution,
            g.cell,
            g.keys,
            g.cache_bytes as f64 / 1024.0
        );
    }
    if say::verbose() {
        print_details(s);
    }
}

fn print_details(s: &RenderStats) {
    let culled = match (s.drawn_triangles_per_sensor, s.selected_triangles_per_sensor) {
        (Some(drawn), Some(selected)) => format!(
            "; {drawn:.0} triangles drawn a sensor of its clusters' {selected:.0}{}",
            if s.whole_clusters > 0 { format!(", {} clusters drawn whole", s.whole_clusters) } else { String::new() }
        ),
        _ => String::new(),
    };
    let rounds: Vec<String> = s.sensors_per_round.iter().map(u64::to_string).collect();
    let fine = match s.fine_sensors {
        0 => String::new(),
        n => format!(", and {n} again at rd {} where a slit fell between texels", FINE_FACTOR * s.sensor_size),
    };
    let read_back: u64 = s.readback_bytes_per_round.iter().sum();
    sensorlight::errln!(
        "{} sensors ({}, rd {}, {}) in {} batches of up to {}, {} in flight; per refinement round: {}; {} quads \
         interpolated; {:.1} KiB read back{culled}",
        s.sensors,
        s.sensor,
        s.sensor_size,
        s.strategy,
        s.batches,
        s.batch_size,
        s.in_flight,
        rounds.join(" + ") + &fine,
        s.interpolated_quads,
        read_back as f64 / 1024.0
    );
    let t = &s.times;
    let gpu = match (t.gpu_maps_seconds, t.gpu_reduction_seconds) {
        (Some(maps), Some(reduction)) => {
            let cull = t.gpu_cull_seconds.map_or(String::new(), |c| format!("{c:.2} s culling + "));
            format!("GPU {cull}{maps:.2} s sensor maps + {reduction:.2} s reduction")
        }
        _ => "no GPU timestamps".into(),
    };
    let cache = match &s.gi {
        Some(_) => format!(
            "radiance cache {:.2} s (first bounce {:.2} s, the others {:.2} s), ",
            t.cache_direct_seconds + t.cache_bounces_seconds,
            t.cache_direct_seconds,
            t.cache_bounces_seconds
        ),
        None => String::new(),
    };
    sensorlight::errln!(
        "{:.2} s total, sensor time {:.4} ms (total / sensors): {cache}G-buffer {:.2} s, sensing {:.2} s (host: \
         record {:.2} s, wait {:.2} s, refine {:.2} s; {gpu}), post {:.2} s; {}",
        s.total_seconds,
        s.sensor_time_ms,
        t.gbuffer_seconds,
        t.sensing_seconds,
        t.host_record_seconds,
        t.host_wait_seconds,
        t.host_refine_seconds,
        t.post_seconds,
        s.device
    );
}

/// Writes `out`'s files, all or none; a frame's (`number`) statistics are numbered as its images.
fn write_outputs(
    args: &RenderArgs,
    (outputs, number): (&super::ImageOutputs, Option<u32>),
    (scene, params): (&Scene, &RenderParams),
    out: &RenderOutput,
    cancel: &Cancel,
) -> Result<()> {
    let (exposure, auto) = super::png_exposure(params, &args.scene, &out.image, &out.gbuffer);
    if let (Some(text), Some(_), true) = (&auto, &outputs.png, say::normal()) {
        sensorlight::errln!("{text}");
    }
    // Every output or none: all are staged, then renamed together.
    let mut files = atomic::Outputs::new();
    match (args.image_tile, &outputs.exr) {
        (Some(tile), Some(path)) => {
            let id = super::tiles::render_id(scene, params, out.size);
            let rule = super::ExposureRule::of(params, &args.scene);
            let exr =
                super::tiles::tile_exr(image_exr(out, true, scene.camera.eye), tile, out.size, (&id, rule, args.aovs))?;
            exr.stage(&mut files, path)?;
        }
        _ => stage_images(&mut files, outputs, out, (exposure, args.aovs), scene.camera.eye)?,
    }
    if let Some(path) = &args.write_scene {
        // The scene file renders as the mesh did: its automatic exposure written down.
        let mut render = scene.render.clone();
        if auto.is_some() {
            render.insert("exposure".into(), toml::Value::Float(format!("{exposure:.1}").parse().unwrap_or(0.0)));
        }
        files.stage_bytes(path, scene.to_toml_with(path, &render)?.as_bytes())?;
    }
    let stats_json =
        args.stats_json.as_ref().map(|p| number.map_or_else(|| p.clone(), |k| super::frames::numbered(p, k)));
    if let Some(path) = &stats_json {
        let json = sensorlight::output::json_text(&out.stats).context("stats to JSON")?;
        files.stage_bytes(path, json.as_bytes())?;
    }
    // Stopped while writing: the staged files go with `files`, the older outputs stay as they were.
    cancel.check()?;
    files.commit()?;
    if say::normal() {
        let extra = [stats_json.as_ref(), args.write_scene.as_ref()];
        for path in outputs.paths().chain(extra.into_iter().flatten()) {
            sensorlight::errln!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// The EXR of `out`: the image, and with `aovs` R, how each pixel was obtained and the G-buffer's layers.
fn image_exr(out: &RenderOutput, aovs: bool, eye: glam::Vec3) -> ExrImage {
    let exr = ExrImage::new(out.size.width, out.size.height).rgba("", &out.image);
    if !aovs {
        return exr;
    }
    let mask = out.radiance.iter().map(|r| match r.w {
        w if w == radiance_state::SENSED => 1.0,
        w if w == radiance_state::INTERPOLATED => 0.5,
        _ => 0.0,
    });
    let mut supersampled = vec![0.0; out.radiance.len()];
    for &i in &out.supersampled {
        supersampled[i as usize] = 1.0;
    }
    let with_r =
        (exr.rgb("radiance", &out.radiance)).scalar("sensor_mask", mask.collect()).scalar("supersampled", supersampled);
    super::gbuffer_aovs(with_r, &out.gbuffer, eye)
}

/// Stages the EXR (with the AOVs if `aovs`) and the PNG at `exposure` that `outputs` names among `files`:
/// `render`'s images, and the viewer's saves.
pub(super) fn stage_images(
    files: &mut atomic::Outputs,
    outputs: &super::ImageOutputs,
    out: &RenderOutput,
    (exposure, aovs): (f32, bool),
    eye: glam::Vec3,
) -> Result<()> {
    let size = out.size;
    if let Some(path) = &outputs.exr {
        image_exr(out, aovs, eye).stage(files, path)?;
    }
    if let Some(path) = &outputs.png {
        png::stage(files, path, (size.width, size.height), &out.image, exposure)?;
    }
    Ok(())
}
