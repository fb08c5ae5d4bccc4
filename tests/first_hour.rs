//! The first hour with real files (issue 24): what a user meets when they stop a render, hand it a
//! third-party OBJ and MTL, or ask for another kind of output.

mod common;

use std::path::Path;
use std::time::{Duration, Instant};

/// Names in `dir`, sorted, hidden (temporary) files included.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// Waits up to `limit` for `done`, polling.
fn wait_for(limit: Duration, mut done: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < limit {
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    false
}

/// A render stopped by SIGINT (Ctrl-C) or SIGTERM once it is sensing (its preview is on disk): it says
/// "interrupted" once, exits 130 or 143, tears down without a validation message, and leaves no preview, no
/// temporary file and no output, while the outputs an earlier run left stay as they were.
#[test]
fn a_signal_stops_a_render_and_leaves_no_file() {
    for (signal, code) in [("INT", 130), ("TERM", 143)] {
        let dir = common::scratch(&format!("signal-{signal}"));
        let out = dir.join("out.exr");
        std::fs::write(&out, b"an earlier EXR").unwrap();
        std::fs::write(dir.join("out.png"), b"an earlier PNG").unwrap();
        let before = listing(&dir);
        // Direct light only: the first round's preview comes at once, the render takes some 30 s after it.
        let mut child = common::command()
            .args(["render", "scenes/room/room.toml", "-o", out.to_str().unwrap()])
            .args(["--width", "128", "--height", "128", "--bounces", "0", "--preview-every", "1"])
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let preview = dir.join("out.preview.png");
        let started = wait_for(Duration::from_secs(120), || preview.exists() || child.try_wait().unwrap().is_some());
        if !preview.exists() {
            let run = child.wait_with_output().unwrap();
            panic!("{signal}: no preview appeared ({}): {}", run.status, common::stderr(&run));
        }
        assert!(started);
        let sent = std::process::Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status();
        assert!(sent.unwrap().success(), "{signal}: kill failed");
        let sent_at = Instant::now();
        let run = child.wait_with_output().unwrap();
        let stderr = common::stderr(&run);
        assert_eq!(run.status.code(), Some(code), "{signal}: {stderr}");
        assert!(sent_at.elapsed() < Duration::from_secs(20), "{signal}: took {:?} to stop", sent_at.elapsed());
        assert_eq!(stderr.matches("interrupted").count(), 1, "{signal}: said once: {stderr}");
        for unwanted in ["validation", "panicked", "error", "wrote "] {
            assert!(!stderr.contains(unwanted), "{signal}: {unwanted:?} in {stderr}");
        }
        assert_eq!(listing(&dir), before, "{signal}: no preview, temporary or new output left");
        assert_eq!(std::fs::read(&out).unwrap(), b"an earlier EXR", "{signal}");
        assert_eq!(std::fs::read(dir.join("out.png")).unwrap(), b"an earlier PNG", "{signal}");
    }
}

/// `reference` and `metrics` stopped by SIGINT once their progress shows (a line on a log, as stderr is
/// here: `reference`'s rows, `metrics`' first render): each says "interrupted" once, exits 130, and writes
/// nothing (issue 42, item 10: both ended without a word, and `reference` showed no progress on a log).
#[test]
fn reference_and_metrics_show_progress_and_stop_on_a_signal() {
    use std::io::BufRead as _;
    let dir = common::scratch("signal-reference-metrics");
    let exr = dir.join("reference.exr");
    let metrics = dir.join("metrics");
    let runs: [(&[&str], &str); 2] = [
        (
            &["reference", "scenes/room/room.toml", "-o", exr.to_str().unwrap(), "--width", "64", "--height", "64"],
            " rows (",
        ),
        (&["metrics", "--quick", "-o", metrics.to_str().unwrap()], "ms/sensor"),
    ];
    for (args, progress) in runs {
        let mut child = common::command().args(args).stderr(std::process::Stdio::piped()).spawn().unwrap();
        let lines = std::io::BufReader::new(child.stderr.take().unwrap()).lines();
        let (send, receive) = std::sync::mpsc::channel();
        let reader = std::thread::spawn(move || {
            for line in lines.map_while(Result::ok) {
                let _ = send.send(line);
            }
        });
        let mut said = Vec::new();
        while let Ok(line) = receive.recv_timeout(Duration::from_secs(180)) {
            let shown = line.contains(progress);
            said.push(line);
            if shown {
                break;
            }
        }
        assert!(said.last().is_some_and(|l| l.contains(progress)), "{args:?}: no progress line: {said:#?}");
        let sent = std::process::Command::new("kill").args(["-INT", &child.id().to_string()]).status();
        assert!(sent.unwrap().success(), "kill failed");
        let status = child.wait().unwrap();
        reader.join().unwrap();
        said.extend(receive.try_iter());
        let stderr = said.join("\n");
        assert_eq!(status.code(), Some(130), "{args:?}: {stderr}");
        assert_eq!(stderr.matches("interrupted").count(), 1, "{args:?}: said once: {stderr}");
        for unwanted in ["validation", "panicked", "error", "wrote "] {
            assert!(!stderr.contains(unwanted), "{args:?}: {unwanted:?} in {stderr}");
        }
    }
    assert_eq!(listing(&dir), Vec::<String>::new(), "nothing written");
}

/// A number followed by a stray `.` (McGuire's `CornellBox-Sphere.obj`, line 5753: `v  0.2300 1.9900
/// -0.2200.`) no longer refuses the whole file: the mesh renders and the warning names the file and line.
/// Garbage is still refused with its line.
#[test]
fn a_stray_dot_after_a_number_renders_with_a_warning() {
    let dir = common::scratch("stray-dot");
    let obj = dir.join("mesh.obj");
    std::fs::write(&obj, "v -1 -1 0\nv 1 -1 0\nv  0.2300 1.9900 -0.2200.\nf 1 2 3\n").unwrap();
    let out = dir.join("out.exr");
    let run = common::sensorlight(&[
        "render",
        obj.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--sensor-size",
        "16",
        "--bounces",
        "0",
    ]);
    let stderr = common::stderr(&run);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("mesh.obj:3: '-0.2200.' read as -0.2200"), "{stderr}");
    assert!(out.exists() && dir.join("out.png").exists());

    std::fs::write(&obj, "v -1 -1 0\nv 1 -1 0\nv 0.23 1.2.3 -0.22\nf 1 2 3\n").unwrap();
    common::expect_failure(
        &["render", obj.to_str().unwrap(), "-o", out.to_str().unwrap()],
        "mesh.obj:3: 'v' has a value that is not a number: '1.2.3'",
    );
}

/// Mirrors, glass and bump maps render as plain diffuse: said once per material, naming what is ignored;
/// what exporters write on diffuse materials (`Ks 0 0 0`, `illum 2`, `Ni 1.5` on an opaque wall) is not.
#[test]
fn ignored_material_data_is_said_once_per_material() {
    let dir = common::scratch("unrendered");
    let mtl = "newmtl glass\nKd 0.2 0.2 0.2\nNi 1.5\nTf 0.9 0.9 0.9\nillum 7\n\
               newmtl wall\nKd 0.7 0.7 0.7\nKs 0 0 0\nNs 10\nNi 1.5\nillum 2\n\
               newmtl brick\nKd 0.5 0.2 0.1\nbump brick.png\nbump brick.png\n";
    std::fs::write(dir.join("materials.mtl"), mtl).unwrap();
    let obj = "mtllib materials.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl glass\nf 1 2 3\nusemtl wall\nf 2 4 3\n\
               usemtl brick\nf 1 3 4\nusemtl glass\nf 1 2 4\n";
    std::fs::write(dir.join("mesh.obj"), obj).unwrap();
    let size = sensorlight::scene::ImageSize { width: 8, height: 8 };
    let scene = sensorlight::scene::Scene::from_mesh(&dir.join("mesh.obj"), size).unwrap();
    let said: Vec<&String> = scene.warnings.iter().filter(|w| w.contains("ignored (treated as diffuse)")).collect();
    let glass = format!(
        "{}: material 'glass': Ni, Tf, illum 7 ignored (treated as diffuse)",
        dir.join("materials.mtl").display()
    );
    assert_eq!(said.len(), 2, "{:?}", scene.warnings);
    assert_eq!(said[0], &glass);
    assert!(said[1].ends_with("material 'brick': bump ignored (treated as diffuse)"), "{}", said[1]);
}

/// `-o out.png` writes the PNG alone; `-o out.exr` the EXR and the PNG beside it; another kind is refused
/// naming the kinds accepted, and so is `--aovs` with a PNG alone (the layers live in the EXR).
#[test]
fn the_output_name_says_which_kinds_are_written() {
    let tiny = ["--width", "16", "--height", "12", "--sensor-size", "16", "--bounces", "0"];
    for (name, written) in [("out.png", &["out.png"][..]), ("out.exr", &["out.exr", "out.png"][..])] {
        let dir = common::scratch(&format!("kinds-{name}"));
        let out = dir.join(name);
        let mut args = vec!["render", "scenes/cornell/cornell.toml", "-o", out.to_str().unwrap()];
        args.extend_from_slice(&tiny);
        let run = common::sensorlight(&args);
        let stderr = common::stderr(&run);
        assert!(run.status.success(), "{name}: {stderr}");
        assert_eq!(listing(&dir), written, "{name}");
        for file in written {
            assert!(stderr.contains(&format!("wrote {}", dir.join(file).display())), "{name}: {stderr}");
        }
        let png = std::fs::read(dir.join("out.png")).unwrap();
        let info = png::Decoder::new(std::io::Cursor::new(png)).read_info().unwrap().info().clone();
        assert_eq!((info.width, info.height), (16, 12), "{name}");
    }
    let dir = common::scratch("kinds-refused");
    let tif = dir.join("out.tif");
    let stderr =
        common::expect_failure(&["render", "scenes/cornell/cornell.toml", "-o", tif.to_str().unwrap()], "out.tif");
    assert!(stderr.contains("expected an .exr file name") && stderr.contains("or a .png one"), "{stderr}");
    let png = dir.join("out.png");
    common::expect_failure(
        &["render", "scenes/cornell/cornell.toml", "-o", png.to_str().unwrap(), "--aovs"],
        "--aovs writes its layers into the EXR",
    );
    assert!(listing(&dir).is_empty());
}

/// `compare --layer radiance` on a render without AOVs says the file has no such layer, what it has, and to
/// render with `--aovs`.
#[test]
fn compare_names_a_missing_layer_and_how_to_get_it() {
    use glam::Vec4;
    use sensorlight::output::exr::ExrImage;
    let dir = common::scratch("compare-layer");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    ExrImage::new(2, 2).rgb("", &[Vec4::splat(0.5); 4]).write(&a).unwrap();
    ExrImage::new(2, 2).rgb("", &[Vec4::splat(0.5); 4]).write(&b).unwrap();
    let stderr = common::expect_failure(
        &["compare", "--layer", "radiance", a.to_str().unwrap(), b.to_str().unwrap()],
        "a.exr has no layer 'radiance' to compare (it has only the main R, G, B)",
    );
    assert!(stderr.contains("render with --aovs"), "{stderr}");
}

/// The global -v/-q help, shown by every command, does not promise compare a device or a strategy.
#[test]
fn compare_help_says_what_verbose_and_quiet_do_there() {
    let run = common::sensorlight(&["compare", "--help"]);
    let help = String::from_utf8_lossy(&run.stdout).into_owned();
    assert!(run.status.success(), "{help}");
    let verbose = help.lines().skip_while(|l| !l.contains("--verbose")).take(4).collect::<Vec<_>>().join(" ");
    assert!(!verbose.contains("Say more: the device"), "{verbose}");
    assert!(verbose.contains("compare have nothing more to say"), "{verbose}");
    let quiet = help.lines().skip_while(|l| !l.contains("--quiet")).take(3).collect::<Vec<_>>().join(" ");
    assert!(quiet.contains("results on standard output"), "{quiet}");
}

/// A mesh named by a bare file name whose MTL is missing: the warning names the directory looked in (`.`),
/// not an empty one.
#[test]
fn a_missing_mtl_beside_a_relative_mesh_names_its_directory() {
    let dir = common::scratch("relative-mtl");
    std::fs::write(dir.join("mesh.obj"), "mtllib mesh.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n").unwrap();
    let run = common::command()
        .current_dir(&dir)
        .args(["render", "mesh.obj", "-o", "out.png", "--width", "8", "--height", "8"])
        .args(["--sensor-size", "16", "--bounces", "0"])
        .output()
        .unwrap();
    let stderr = common::stderr(&run);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("material library 'mesh.mtl' not found (looked in . and for its file name there)"),
        "{stderr}"
    );
    assert!(!stderr.contains("looked in  and"), "{stderr}");
}

/// `render --help` says that a mesh without emitters is lit by a white sky, where it names the background's
/// default.
#[test]
fn render_help_names_the_white_sky() {
    let run = common::sensorlight(&["render", "--help"]);
    let help = String::from_utf8_lossy(&run.stdout).into_owned();
    let background = help.lines().skip_while(|l| !l.contains("--background")).take(3).collect::<Vec<_>>().join(" ");
    assert!(background.contains("nothing emits: 1,1,1, a white sky"), "{background}");
}
