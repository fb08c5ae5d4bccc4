//! The command line as a user meets it: device listing, missing drivers, renders that write real files.

mod common;

use sensorlight::output::exr;
use sensorlight::vk::{adapter, instance::Instance};

#[test]
fn devices_lists_every_device_with_its_limits() {
    let run = common::sensorlight(&["devices"]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let stdout = String::from_utf8_lossy(&run.stdout);
    let instance = Instance::new(false, &[]).unwrap();
    let adapters = adapter::enumerate(&instance, &sensorlight::passes::requirements()).unwrap();
    for a in &adapters {
        assert!(stdout.contains(&format!("[{}] {}", a.index, a.name)), "{} missing from:\n{stdout}", a.name);
        assert!(stdout.contains(&format!("maxMultiviewViewCount {}", a.limits.max_multiview_view_count)));
        assert!(stdout.contains(&format!("maxFramebufferLayers {}", a.limits.max_framebuffer_layers)));
    }
    assert!(stdout.contains("shaderOutputLayer"));
    assert_eq!(stdout.matches("(default)").count(), 1, "exactly one default device:\n{stdout}");
}

#[test]
fn no_driver_says_how_to_install_one() {
    for command in [&["devices"][..], &["render", "scenes/cornell/cornell.toml", "-o", "never.exr"]] {
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_sensorlight"))
            .args(command)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
            .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
            .output()
            .unwrap();
        let stderr = common::stderr(&run);
        assert_eq!(run.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains("mesa-vulkan-drivers") && !stderr.contains("panicked"), "{stderr}");
        assert!(!common::project("never.exr").exists());
    }
}

/// Renders a scene through the CLI into a fresh directory; returns the directory.
fn render(scene: &str, name: &str, extra: &[&str]) -> std::path::PathBuf {
    let dir = common::scratch(name);
    let out = dir.join("out.exr");
    let mut args = vec!["render", scene, "-o", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let run = common::sensorlight(&args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let stderr = common::stderr(&run);
    assert!(stderr.contains("sensor time"), "prints its statistics: {stderr}");
    assert!(stderr.contains("; strategy "), "says which batching strategy it uses: {stderr}");
    // Standard error is a pipe here: plain progress lines, ending with the whole image resolved.
    assert!(stderr.contains("100 % of pixels resolved"), "{stderr}");
    dir
}

#[test]
fn render_writes_image_aovs_and_stats_of_both_cornell_boxes() {
    let small = ["--width", "40", "--height", "30", "--sensor-size", "16", "--aovs", "--stats-json"];
    for (scene, name) in [
        ("scenes/cornell/cornell.toml", "render_cornell"),
        ("scenes/cornell-mcguire/cornell-mcguire.toml", "render_mcguire"),
    ] {
        let dir = common::scratch(name);
        let stats_path = dir.join("stats.json");
        let mut flags = small.to_vec();
        flags.push(stats_path.to_str().unwrap());
        let dir = render(scene, name, &flags);
        assert!(dir.join("out.png").exists(), "PNG preview beside the EXR");
        let channels = ["R", "G", "B", "radiance.R", "sensor_mask", "surface_id"];
        let (w, h, c) = exr::read_channels(&dir.join("out.exr"), &channels).unwrap();
        assert_eq!((w, h), (40, 30));
        assert!(c[0].iter().any(|&r| r > 0.05), "{name}: the image is lit");
        // Where the mask says sensed or interpolated there is a surface; the background has neither.
        for (i, (mask, id)) in c[4].iter().zip(&c[5]).enumerate() {
            assert_eq!(*mask > 0.0, *id > 0.0, "{name}: pixel {i} mask vs surface id");
        }
        let stats_text = std::fs::read_to_string(&stats_path).unwrap();
        assert!(stats_text.ends_with("}\n"), "{name}: the JSON ends with a newline");
        let stats: serde_json::Value = serde_json::from_str(&stats_text).unwrap();
        assert!(stats["build_seconds"].as_f64().is_some(), "{name}: the strategy choice's time is reported");
        let sensed = c[4].iter().filter(|&&m| m == 1.0).count() as u64;
        assert_eq!(stats["sensors"].as_u64(), Some(sensed), "{name}: sensors counted = sensors in the mask");
        assert_eq!(stats["sensor_size"].as_u64(), Some(16));
        assert!(stats["sensor_time_ms"].as_f64().unwrap() > 0.0);
        // Each round reads back what the sensors it placed found (R and visibilities), not the whole map.
        let per_round =
            |key: &str| -> Vec<u64> { stats[key].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect() };
        let (placed, read) = (per_round("sensors_per_round"), per_round("readback_bytes_per_round"));
        let per_sensor = size_of::<sensorlight::gpu_types::GpuSensorResult>() as u64;
        assert_eq!(read, placed.iter().map(|n| per_sensor * n).collect::<Vec<_>>(), "{name}: read-back per round");
        // The host's own work and waits lie within the sensing phase; the phases within the total.
        let t = &stats["times"];
        let f = |key: &str| t[key].as_f64().unwrap_or_else(|| panic!("{name}: times.{key} missing"));
        let host = f("host_record_seconds") + f("host_wait_seconds") + f("host_refine_seconds");
        assert!(host <= f("sensing_seconds") + 1e-6, "{name}: host {host} > sensing {}", f("sensing_seconds"));
        let phases = f("gbuffer_seconds") + f("sensing_seconds") + f("post_seconds");
        assert!(phases <= stats["total_seconds"].as_f64().unwrap() + 1e-6, "{name}: phases exceed the total");
    }
}

#[test]
fn a_tiny_memory_budget_means_more_batches_not_failure() {
    let dir = common::scratch("memory_budget");
    let stats = dir.join("stats.json");
    render(
        "scenes/cornell/cornell.toml",
        "memory_budget",
        &[
            "--width",
            "16",
            "--height",
            "16",
            "--sensor-size",
            "64",
            "--memory-budget",
            "1",
            // A batching strategy named: `auto` may measure per-sensor fastest on a busy machine, and
            // per-sensor holds one sensor whatever the budget.
            "--strategy",
            "layered",
            "--stats-json",
            stats.to_str().unwrap(),
        ],
    );
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    // Three quarters of 1 MiB (the radiance cache's later bounces take the rest) hold 3 hemicube sensors of
    // 64² with the Cornell light's zoom pair: (3 + 2) layers × 64² texels × (8 colour + 4 depth) bytes =
    // 240 KiB each.
    assert_eq!(stats["batch_size"].as_u64(), Some(3));
    assert!(stats["batches"].as_u64().unwrap() >= stats["sensors"].as_u64().unwrap() / 3);
}

/// The default render is global illumination, said in its summary; a material reflecting more than the
/// bounces allow is warned about once, before the work.
#[test]
fn global_illumination_is_the_default_and_says_what_it_did() {
    let dir = common::scratch("render_gi");
    let (mesh, mtl) = (dir.join("bright.obj"), dir.join("bright.mtl"));
    std::fs::write(&mtl, "newmtl snow\nKd 1.2 1.2 1.2\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 5 5 5\n").unwrap();
    let obj = "mtllib bright.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\n\
               usemtl snow\nf 1 2 3 4\nusemtl lamp\nf 5 8 7 6\n";
    std::fs::write(&mesh, obj).unwrap();
    let out = dir.join("bright.exr");
    let render = |extra: &[&str]| {
        let mut args = vec!["render", mesh.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "8"];
        args.extend(["--height", "8"]);
        args.extend(extra);
        common::sensorlight(&args)
    };
    let run = render(&[]);
    let stderr = common::stderr(&run);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("global illumination: "), "{stderr}");
    assert_eq!(stderr.matches("global illumination's bounces use at most 0.98").count(), 1, "{stderr}");
    let direct = render(&["--bounces", "0"]);
    let stderr = common::stderr(&direct);
    assert!(direct.status.success() && !stderr.contains("global illumination"), "{stderr}");
}

#[test]
fn bad_render_parameters_are_clear_errors() {
    let scene = common::project("scenes/cornell/cornell.toml");
    let cases: [(&[&str], &str); 17] = [
        (&["--width", "0"], "--width"),
        // Said as negative, not with clap's tip to pass it after `--`.
        (&["--width", "-5"], "'--width <WIDTH>': -5 is negative; a whole number of 0 or more is expected"),
        (&["--tile", "-8"], "-8 is negative"),
        (&["--bounces", "-1"], "expected a count of bounces (0, 1, 2, …) or 'auto'"),
        (&["--bounces", "many"], "expected a count of bounces"),
        (&["--bounces", "2", "--epsilon", "0.1"], "--bounces 2 cannot be combined with --epsilon 0.1"),
        (&["--cache-resolution", "0"], "--cache-resolution must be 1 to 1022 cells"),
        (&["--cache-sensor-size", "7"], "--cache-sensor-size"),
        (&["--sensor-size", "0"], "--sensor-size"),
        (&["--fov", "0"], "--fov"),
        (&["--sensor-size", "1000000"], "--sensor-size 1000000 exceeds this device"),
        (&["--sensor-size", "15"], "even"),
        (&["--sensor", "frustum", "--fov", "180"], "--fov"),
        (&["--epsilon", "-0.5"], "--epsilon"),
        (&["--tile", "12"], "--tile must be a power of two"),
        (&["--dradiance", "-1"], "--dradiance"),
        (&["--filter-radius", "181"], "--filter-radius must be at most 64"),
    ];
    for (flags, expected) in cases {
        let out = common::scratch("render_bad").join("x.exr");
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()];
        args.extend_from_slice(flags);
        common::expect_failure(&args, expected);
        assert!(!out.exists() && !out.with_extension("png").exists());
    }
}

/// What a user reads about a tiny image and about the viewer's script (issue 42, item 9): a 1 × 1 render
/// counts its one sensor as one ("1 sensor", not "1 sensors" nor "0 sensors"), and `view --help` names
/// every script command, `resize` among them, and every view `show` takes.
#[test]
fn a_one_pixel_render_and_the_viewers_help_say_it_right() {
    let out = common::scratch("render_one_pixel").join("one.exr");
    let scene = common::project("scenes/cornell/cornell.toml");
    let args = ["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "1", "--height", "1"];
    let run = common::sensorlight(&args);
    let stderr = common::stderr(&run);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("): 1 sensor, sensor time"), "{stderr}");
    let help = String::from_utf8_lossy(&common::sensorlight(&["view", "--help"]).stdout).into_owned();
    for word in ["resize WIDTH HEIGHT", "show VIEW", "wait done", "save F.exr"] {
        assert!(help.contains(word), "view --help lacks {word:?}: {help}");
    }
    for show in sensorlight::viewer::Show::ALL {
        assert!(help.contains(show.word()), "view --help lacks the view {:?}: {help}", show.word());
    }
}

/// Outputs that cannot be written are refused before the scene is even loaded, not after a long render.
#[test]
fn unwritable_outputs_are_refused_before_any_work() {
    let dir = common::scratch("render_unwritable");
    let exr = dir.join("x.exr");
    let missing = dir.join("missing/x.exr");
    let (exr, missing, dir_s) = (exr.to_str().unwrap(), missing.to_str().unwrap(), dir.to_str().unwrap());
    // The scene does not exist either: the output is checked first.
    let png = format!("{dir_s}/x.png");
    let cases: [(&[&str], &str); 8] = [
        (&["-o", missing], "does not exist"),
        (&["-o", "-"], "-o -: standard output is not supported"),
        (&["-o", dir_s], "expected an .exr file name"),
        (&["-o", &format!("{dir_s}/x.tif")], "or a .png one (the PNG alone)"),
        (&["-o", &png, "--aovs"], "--aovs writes its layers into the EXR"),
        (&["-o", &png, "--no-png"], "nothing would be written"),
        (&["-o", exr, "--stats-json", dir_s], "is a directory"),
        (&["-o", exr, "--stats-json", &format!("{dir_s}/missing/s.json")], "does not exist"),
    ];
    for (flags, expected) in cases {
        let mut args = vec!["render", "no-such-scene.toml"];
        args.extend_from_slice(flags);
        common::expect_failure(&args, expected);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "{flags:?} left a file behind");
    }
    common::expect_failure(&["reference", "no-such-scene.toml", "-o", missing], "does not exist");
    common::expect_failure(&["render", "no-such-scene.toml", "-o", exr], "no-such-scene.toml");
}

/// Runs `sensorlight args` with its standard output a pipe whose reader has already gone, as in
/// `sensorlight devices | head -0`: the first line it prints meets a closed pipe.
fn with_closed_stdout(args: &[&str]) -> std::process::Output {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let child = common::command().args(args).stdout(writer).stderr(std::process::Stdio::piped()).spawn().unwrap();
    child.wait_with_output().unwrap()
}

/// A reader that stops reading is no failure: every command that prints to stdout ends quietly, exit 0,
/// and still writes its files.
#[test]
fn a_closed_stdout_ends_quietly() {
    let dir = common::scratch("closed_stdout");
    let image = dir.join("a.exr");
    exr::ExrImage::new(2, 1).rgb("", &[glam::Vec4::ONE, glam::Vec4::splat(2.0)]).write(&image).unwrap();
    let (image, json) = (image.to_str().unwrap(), dir.join("bench.json"));
    let bench = ["bench", "--sizes", "8", "--sensors", "2", "--repeat", "1", "--strategies", "per-sensor"];
    let mut bench = bench.to_vec();
    bench.extend(["--json", json.to_str().unwrap()]);
    for args in [&["devices"][..], &["compare", image, image], &bench] {
        let run = with_closed_stdout(args);
        let stderr = common::stderr(&run);
        assert_eq!(run.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked") && !stderr.contains("error"), "{args:?}: {stderr}");
    }
    assert!(json.exists(), "bench wrote its report before the table");
}

/// Standard output on a full disk (`> /dev/full`) is an error like any other: exit 1, said once.
#[test]
fn a_full_stdout_is_an_error_said_once() {
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let run = common::command().arg("devices").stdout(full).output().unwrap();
    let stderr = common::stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("cannot write to standard output"), "{stderr}");
    assert_eq!(stderr.matches("No space left on device").count(), 1, "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// Every long flag `--help` shows is documented in docs/USAGE.md: a command's flags in its own section
/// (`### \`sensorlight COMMAND …\``), the global ones (`-v`, `-q`) anywhere.
#[test]
fn every_flag_in_help_is_in_the_usage_guide() {
    // The README stays short for a newcomer (issue 40, item 6): the reference is docs/USAGE.md.
    let short = std::fs::read_to_string(common::project("README.md")).unwrap();
    assert!(
        short.lines().count() <= 150,
        "README.md has {} lines; the reference goes to docs/USAGE.md",
        short.lines().count()
    );
    let readme = std::fs::read_to_string(common::project("docs/USAGE.md")).unwrap();
    let section = |command: &str| -> &str {
        let heading = format!("### `sensorlight {command}");
        let Some(at) = readme.find(&heading) else { panic!("docs/USAGE.md has no section {heading}`") };
        let rest = &readme[at + heading.len()..];
        let end = [rest.find("\n### "), rest.find("\n## ")].into_iter().flatten().min().unwrap_or(rest.len());
        &rest[..end]
    };
    let has = |text: &str, flag: &str| {
        text.match_indices(flag)
            .any(|(at, _)| !text[at + flag.len()..].starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-'))
    };
    let long_flags = |args: &[&str]| -> Vec<String> {
        let run = common::sensorlight(args);
        assert!(run.status.success(), "{args:?}");
        let help = String::from_utf8_lossy(&run.stdout).into_owned();
        let words = help.split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'));
        let mut flags: Vec<String> = words
            .filter(|w| w.len() > 2 && w.starts_with("--") && w.as_bytes()[2].is_ascii_lowercase())
            .map(str::to_owned)
            .collect();
        flags.dedup();
        flags
    };
    let global = long_flags(&["--help"]);
    assert!(global.contains(&"--verbose".to_owned()) && global.contains(&"--quiet".to_owned()), "{global:?}");
    let mut missing = Vec::new();
    for flag in &global {
        if !has(&readme, flag) && !["--help", "--version"].contains(&flag.as_str()) {
            missing.push(format!("sensorlight {flag}"));
        }
    }
    for command in
        ["devices", "render", "cache", "bake", "assemble", "slurm", "reference", "compare", "bench", "metrics", "view"]
    {
        let text = section(command);
        for flag in long_flags(&[command, "--help"]) {
            if !has(text, &flag) && !global.contains(&flag) {
                missing.push(format!("{command} {flag}"));
            }
        }
    }
    assert!(missing.is_empty(), "flags missing from their docs/USAGE.md sections: {missing:?}");
}

/// The guide's sentence on the scene file's `[render]` table names every parameter's key, from the table.
#[test]
fn every_render_key_is_in_the_usage_guide() {
    let guide = std::fs::read_to_string(common::project("docs/USAGE.md")).unwrap();
    let Some(at) = guide.find("a scene file's `[render]` table may set any of them") else {
        panic!("docs/USAGE.md no longer says which keys `[render]` takes")
    };
    let sentence = &guide[at..at + guide[at..].find(".\n").unwrap_or(guide.len() - at)];
    let missing: Vec<&str> = sensorlight::params::Param::ALL
        .iter()
        .map(|p| p.key())
        .filter(|key| !sentence.contains(&format!("`{key}`")))
        .collect();
    assert!(missing.is_empty(), "[render] keys missing from docs/USAGE.md: {missing:?}");
}

fn tiny(scene: &str, out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["render", scene, "-o", out.to_str().unwrap(), "--width", "16", "--height", "16"];
    args.extend_from_slice(&["--sensor-size", "16"]);
    args.extend_from_slice(extra);
    common::sensorlight(&args)
}

/// Default: progress, the summary and the files; `-q`: nothing; `-v`: the device, the strategy, the rounds.
/// The strategy's self-check refusals (multiview on lavapipe 22.3) are no default business.
#[test]
fn quiet_default_and_verbose_say_what_they_promise() {
    let dir = common::scratch("verbosity");
    let out = dir.join("out.exr");
    let scene = "scenes/cornell/cornell.toml";
    let quiet = tiny(scene, &out, &["-q"]);
    assert!(quiet.status.success() && quiet.stderr.is_empty(), "-q: {}", common::stderr(&quiet));
    let normal = common::stderr(&tiny(scene, &out, &[]));
    assert!(normal.contains("rendered in") && normal.contains("wrote "), "{normal}");
    for detail in ["self-check", "FAILS", "refused", "device: ", "round 1:"] {
        assert!(!normal.contains(detail), "default output says {detail:?}: {normal}");
    }
    let verbose = common::stderr(&tiny(scene, &out, &["-v"]));
    for detail in ["device: ", "strategy: ", "round 1: ", "per refinement round"] {
        assert!(verbose.contains(detail), "-v lacks {detail:?}: {verbose}");
    }
    // A failure still says why with -q.
    let failed = tiny("no-such-scene.toml", &out, &["-q"]);
    assert_eq!(failed.status.code(), Some(1));
    assert!(common::stderr(&failed).contains("no-such-scene.toml"));
}

/// `--preview-every 1` writes OUT.preview.png after each round (said with -v) beside, never over, the final
/// outputs, and removes it when the render is done.
#[test]
fn previews_are_written_each_round_and_removed() {
    let dir = common::scratch("preview");
    let out = dir.join("out.exr");
    let run = tiny("scenes/cornell/cornell.toml", &out, &["--preview-every", "1", "-v"]);
    let stderr = common::stderr(&run);
    assert!(run.status.success(), "{stderr}");
    let preview = dir.join("out.preview.png");
    assert!(stderr.contains(&format!("preview after round 1: {}", preview.display())), "{stderr}");
    assert!(!preview.exists(), "the preview is gone once the render is");
    assert!(out.exists() && dir.join("out.png").exists());
    common::expect_failure(
        &["render", "scenes/cornell/cornell.toml", "-o", out.to_str().unwrap(), "--preview-every", "0"],
        "--preview-every",
    );
}

/// A bare mesh renders with a camera that frames it; `--write-scene` writes that scene as TOML, which loads.
#[test]
fn a_mesh_renders_with_an_automatic_camera_and_writes_its_scene() {
    let dir = common::scratch("mesh_input");
    let out = dir.join("box.exr");
    let toml = dir.join("box.toml");
    // Open towards +z: the automatic camera, looking along −z, sees into it.
    let mesh = common::project("scenes/cornell-mcguire/CornellBox-Original.obj");
    let run = tiny(mesh.to_str().unwrap(), &out, &["--write-scene", toml.to_str().unwrap()]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let (w, h, c) = exr::read_channels(&out, &["R", "G", "B"]).unwrap();
    assert_eq!((w, h), (16, 16));
    assert!(c[0].iter().any(|&r| r > 0.0), "lit");
    let scene = sensorlight::scene::Scene::load(&toml).unwrap();
    assert_eq!(
        scene.mesh.triangles.len(),
        sensorlight::scene::Scene::from_mesh(&mesh, scene.image).unwrap().mesh.triangles.len()
    );
    assert_eq!((scene.image.width, scene.image.height), (16, 16));
    // Only the verbatim OBJ's `mtllib scenes/…`, whose MTL is found by its file name beside it.
    assert!(scene.warnings.iter().all(|w| w.contains("found by file name")), "{:?}", scene.warnings);

    // A mesh with no light is lit by a white sky, and says so.
    std::fs::write(dir.join("quad.obj"), "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv 0 1 0\nf 1 4 3 2\nf 1 2 5\n")
        .unwrap();
    let quad = dir.join("quad.obj");
    let run = tiny(quad.to_str().unwrap(), &dir.join("quad.exr"), &[]);
    let stderr = common::stderr(&run);
    assert!(run.status.success() && stderr.contains("white sky"), "{stderr}");
    assert!(!stderr.contains("no surface emits light"), "the sky answers that warning: {stderr}");
    let (_, _, c) = exr::read_channels(&dir.join("quad.exr"), &["G"]).unwrap();
    assert!(c[0].iter().any(|&g| g > 0.1), "the sky lights the mesh");
}

/// A file of the wrong kind is named as such, with what was expected; nothing is written.
#[test]
fn a_file_of_the_wrong_kind_is_named() {
    let dir = common::scratch("wrong_kind");
    let png = dir.join("picture.png");
    std::fs::write(&png, b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR").unwrap();
    let renamed = dir.join("picture.toml");
    std::fs::copy(&png, &renamed).unwrap();
    let out = dir.join("x.exr");
    let out = out.to_str().unwrap();
    for input in [&png, &renamed] {
        let input = input.to_str().unwrap();
        let stderr = common::expect_failure(
            &["render", input, "-o", out],
            "is a PNG image; expected a scene file (TOML), or an OBJ or glTF mesh",
        );
        assert!(stderr.contains(input), "{stderr}");
    }
    let mesh = common::project("scenes/cornell/cornell.obj");
    let mesh = mesh.to_str().unwrap();
    common::expect_failure(
        &["metrics", "--quick", "--scene", mesh, "-o", dir.to_str().unwrap()],
        "cornell.obj is an OBJ mesh; this command needs a scene file (TOML)",
    );
    common::expect_failure(&["bench", "--scene", mesh, "--sizes", "8"], "needs a scene file (TOML)");
    assert!(!dir.join("x.exr").exists() && !dir.join("metrics.json").exists());
    let err = sensorlight::scene::Scene::load(std::path::Path::new(mesh)).unwrap_err().to_string();
    assert!(err.contains("is an OBJ mesh, not a scene file (TOML)"), "{err}");
}

/// `reference` tone-maps its PNG with the scene's `[render] exposure`, as `render` does.
#[test]
fn reference_honours_the_scenes_exposure() {
    let dir = common::scratch("reference_exposure");
    for f in ["cornell.obj", "cornell.mtl"] {
        std::fs::copy(common::project("scenes/cornell").join(f), dir.join(f)).unwrap();
    }
    let toml = std::fs::read_to_string(common::project("scenes/cornell/cornell.toml")).unwrap();
    assert!(toml.contains("exposure = 1.0"), "the shipped scene sets its exposure");
    std::fs::write(dir.join("scene.toml"), &toml).unwrap();
    std::fs::write(dir.join("plain.toml"), toml.replace("exposure = 1.0", "exposure = 0.0")).unwrap();
    let png = |scene: &str, name: &str, extra: &[&str]| {
        let out = dir.join(format!("{name}.exr"));
        let mut args = vec!["reference", scene, "-o", out.to_str().unwrap(), "--width", "8", "--height", "8"];
        args.extend_from_slice(&["--samples", "4"]);
        args.extend_from_slice(extra);
        let run = common::sensorlight(&args);
        assert!(run.status.success(), "{}", common::stderr(&run));
        std::fs::read(out.with_extension("png")).unwrap()
    };
    let (scene, plain) = (dir.join("scene.toml"), dir.join("plain.toml"));
    let (scene, plain) = (scene.to_str().unwrap(), plain.to_str().unwrap());
    let from_scene = png(scene, "a", &[]);
    assert_eq!(from_scene, png(plain, "b", &["--exposure", "1"]), "the scene's exposure = the flag's");
    assert_ne!(from_scene, png(plain, "c", &[]), "exposure changes the PNG");
}

/// Diagnostics are best effort: with standard error closed a render still runs and writes its outputs
/// (it used to panic on its first message, exit 101, and write nothing); a failure still exits non-zero.
#[test]
fn a_closed_stderr_does_not_stop_a_render() {
    let dir = common::scratch("closed_stderr");
    let out = dir.join("out.exr");
    let run = |extra: &[&str]| {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let scene = common::project("scenes/cornell/cornell.toml");
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "8"];
        args.extend_from_slice(extra);
        common::command().args(&args).stderr(writer).status().unwrap()
    };
    assert_eq!(run(&["--height", "8"]).code(), Some(0));
    assert!(out.exists() && out.with_extension("png").exists());
    assert_eq!(run(&["--height", "0"]).code(), Some(1), "an error is still an exit code");
}
