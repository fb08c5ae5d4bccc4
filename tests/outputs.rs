//! What the commands write, as a user meets it: outputs never clobber one another, an input or a special
//! file; a failed run leaves none of its outputs; a full disk is said once; the same command writes the
//! same bytes.

#![cfg(unix)]

mod common;

use std::os::unix::fs::FileTypeExt as _;
use std::path::{Path, PathBuf};
use std::process::Command;

const CORNELL: &str = "scenes/cornell/cornell.toml";
/// A small, fast CPU reference of the Cornell box.
const SMALL_REFERENCE: [&str; 6] = ["--width", "24", "--height", "16", "--samples", "8"];

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// `--stats-json` (or any output) naming another output or an input is refused before any work, whichever
/// way the name is spelt, and nothing is touched.
#[test]
fn outputs_that_name_the_same_file_are_refused() {
    let dir = common::scratch("outputs_alias");
    std::fs::create_dir(dir.join("sub")).unwrap();
    let exr = dir.join("out.exr");
    std::fs::write(dir.join("out.png"), b"old preview").unwrap();
    std::os::unix::fs::symlink(dir.join("out.png"), dir.join("link.json")).unwrap();
    let scene = common::project(CORNELL);
    let cases = [
        (dir.join("out.exr"), "same file"),
        (dir.join("out.png"), "same file"),
        (dir.join("sub/../out.png"), "same file"),
        (dir.join("link.json"), "same file"),
        (scene.clone(), "would overwrite the input"),
    ];
    for (stats, expected) in &cases {
        let args = ["render", path(&scene), "-o", path(&exr), "--stats-json", path(stats)];
        let stderr = common::expect_failure(&args, expected);
        assert!(stderr.contains("--stats-json"), "names the flag: {stderr}");
        assert_eq!(listing(&dir), ["link.json", "out.png", "sub"], "{stats:?}");
        assert_eq!(std::fs::read(dir.join("out.png")).unwrap(), b"old preview");
    }
    // The mesh and its materials are inputs too, known once the scene is read.
    let copy = dir.join("scene");
    std::fs::create_dir(&copy).unwrap();
    for name in ["cornell.toml", "cornell.obj", "cornell.mtl"] {
        std::fs::copy(common::project(&format!("scenes/cornell/{name}")), copy.join(name)).unwrap();
    }
    let mtl = std::fs::read(copy.join("cornell.mtl")).unwrap();
    let (small, toml) = (["--width", "8", "--height", "8", "--sensor-size", "8"], copy.join("cornell.toml"));
    for input in ["cornell.mtl", "cornell.obj"] {
        let mut args = vec!["render", path(&toml), "-o", path(&exr), "--no-png", "--stats-json"];
        let stats = dir.join("sub/../scene").join(input);
        args.push(path(&stats));
        args.extend_from_slice(&small);
        common::expect_failure(&args, "would overwrite the input");
    }
    assert_eq!(std::fs::read(copy.join("cornell.mtl")).unwrap(), mtl, "the MTL is untouched");
    assert!(!exr.exists());
    // bench's reports (checked before the scene is even read), and compare's --json against its inputs.
    let json = dir.join("r.json");
    let (json, csv) = (path(&json), path(&dir.join("sub/../r.json")).to_owned());
    common::expect_failure(&["bench", "--scene", "no-such-scene.toml", "--json", json, "--csv", &csv], "same file");
    let image = dir.join("image.exr");
    sensorlight::output::exr::ExrImage::new(2, 1).scalar("R", vec![1.0, 2.0]).write(&image).unwrap();
    let before = std::fs::read(&image).unwrap();
    let stderr = common::expect_failure(&["compare", path(&image), path(&image), "--json", path(&image)], "--json");
    assert!(stderr.contains("would overwrite the input"), "{stderr}");
    assert_eq!(std::fs::read(&image).unwrap(), before, "the input is untouched");
}

/// A FIFO, a device, a directory or a link to one of them is never replaced by a regular file; a link to a
/// regular file is written through, and stays a link.
#[test]
fn special_files_are_refused_and_links_written_through() {
    let dir = common::scratch("outputs_special");
    let fifo = dir.join("stats.json");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    std::os::unix::fs::symlink("/dev/null", dir.join("null.exr")).unwrap();
    std::fs::create_dir(dir.join("out.png")).unwrap();
    let (exr, scene, null) = (dir.join("out.exr"), common::project(CORNELL), dir.join("null.exr"));
    let cases: [(&[&str], &str); 4] = [
        (&["-o", path(&exr), "--no-png", "--stats-json", path(&fifo)], "named pipe"),
        (&["-o", path(&null), "--no-png"], "symbolic link to /dev/null"),
        (&["-o", path(&exr)], "is a directory"),
        (&["-o", path(&exr), "--no-png", "--stats-json", "/dev/null"], "is a device"),
    ];
    for (flags, expected) in cases {
        let mut args = vec!["render", path(&scene)];
        args.extend_from_slice(flags);
        common::expect_failure(&args, expected);
    }
    assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo(), "the FIFO is still a FIFO");
    assert!(std::fs::symlink_metadata(dir.join("null.exr")).unwrap().file_type().is_symlink());
    assert!(!exr.exists());

    std::fs::create_dir(dir.join("results")).unwrap();
    let real = dir.join("results/real.exr");
    std::fs::write(&real, b"old").unwrap();
    let link = dir.join("link.exr");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let mut args = vec!["reference", CORNELL, "-o", path(&link), "--no-png"];
    args.extend_from_slice(&SMALL_REFERENCE);
    let run = common::sensorlight(&args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "the link stays a link");
    let (w, h, _) = sensorlight::output::exr::read_channels(&real, &["R"]).unwrap();
    assert_eq!((w, h), (24, 16), "its target holds the new image");
    assert_eq!(listing(&dir.join("results")), ["real.exr"], "no temporary left beside the target");
}

/// Runs `script` with `sh` in a new user and mount namespace, where it may mount a small tmpfs; `None` where
/// this system allows no such namespace.
fn in_mount_namespace(script: &str, args: &[&str]) -> Option<std::process::Output> {
    let probe = Command::new("unshare").args(["-rm", "true"]).output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!("skipped: unshare -rm is not permitted here, so no small file system can be mounted");
        return None;
    }
    let mut command = Command::new("unshare");
    command.args(["-rm", "sh", "-c", script, "sh"]).args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    command.env("SENSORLIGHT_CACHE_DIR", Path::new(env!("CARGO_TARGET_TMPDIR")).join("strategy-cache"));
    Some(command.output().unwrap())
}

/// On a small file system (a tmpfs in a private mount namespace): the EXR does not fit, and the message
/// says "No space left on device" once; the EXR fits but the PNG after it does not, and the EXR is not left
/// behind (a failed run leaves no output of its own) while the PNG that was there before is kept.
#[test]
fn a_full_disk_leaves_no_output_and_is_said_once() {
    let dir = common::scratch("outputs_full");
    let probe = dir.join("probe.exr");
    let mut args = vec!["reference", CORNELL, "-o", path(&probe)];
    args.extend_from_slice(&SMALL_REFERENCE);
    let run = common::sensorlight(&args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let exr_pages = std::fs::metadata(&probe).unwrap().len().div_ceil(4096);
    let mnt = dir.join("mnt");
    std::fs::create_dir(&mnt).unwrap();
    // $1 binary, $2 mount point, $3 tmpfs size in KiB; the rest are sensorlight's arguments.
    let script = r#"bin=$1; mnt=$2; size=$3; shift 3
        mount -t tmpfs -o size=${size}k tmpfs "$mnt" || exit 99
        printf 'old preview' > "$mnt/out.png"
        "$bin" "$@"; code=$?
        echo "listing: $(ls -A "$mnt" | tr '\n' ' ')"
        echo "png: $(cat "$mnt/out.png")"
        exit $code"#;
    let out = path(&mnt.join("out.exr")).to_owned();
    for (case, pages) in [("the EXR does not fit", 1), ("the PNG does not fit", exr_pages + 1)] {
        let size = (pages * 4).to_string();
        let mut args = vec![env!("CARGO_BIN_EXE_sensorlight"), path(&mnt), &size, "reference", CORNELL, "-o", &out];
        args.extend_from_slice(&SMALL_REFERENCE);
        let Some(run) = in_mount_namespace(script, &args) else { return };
        let (stdout, stderr) = (String::from_utf8_lossy(&run.stdout), common::stderr(&run));
        assert_eq!(run.status.code(), Some(1), "{case}: {stdout}{stderr}");
        assert_eq!(stderr.matches("No space left on device").count(), 1, "{case}: said once: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(stdout.contains("listing: out.png \n"), "{case}: no output and no temporary left: {stdout}");
        assert!(stdout.contains("png: old preview"), "{case}: the old PNG is untouched: {stdout}");
    }
}

fn without_times(mut stats: serde_json::Value) -> serde_json::Value {
    for key in ["total_seconds", "build_seconds", "times", "sensor_time_ms"] {
        assert!(stats.get(key).is_some(), "{key} missing");
        stats[key] = serde_json::Value::Null;
    }
    assert!(stats["gi"]["bounces"].as_u64().is_some(), "the default render has global illumination");
    stats
}

/// The same command twice writes the same bytes: EXR, PNG, and the stats JSON but for its measured times.
#[test]
fn the_same_render_twice_writes_the_same_bytes() {
    let dirs: Vec<PathBuf> = (0..2).map(|i| common::scratch(&format!("outputs_deterministic_{i}"))).collect();
    // A cache of its own: `auto` picks the strategy in the first run, the second reads that choice (a test
    // running beside it must not change it in between).
    let cache = common::scratch("outputs_deterministic_cache");
    for dir in &dirs {
        let (exr, stats) = (dir.join("out.exr"), dir.join("stats.json"));
        let args = ["render", CORNELL, "-o", path(&exr), "--width", "24", "--height", "16", "--sensor-size", "8"];
        let mut args = args.to_vec();
        args.extend(["--aovs", "--stats-json", path(&stats)]);
        let run = common::command().args(&args).env("SENSORLIGHT_CACHE_DIR", &cache).output().unwrap();
        assert!(run.status.success(), "{}", common::stderr(&run));
    }
    let read = |dir: &PathBuf, name: &str| std::fs::read(dir.join(name)).unwrap();
    let channels = ["R", "G", "B", "radiance.R", "sensor_mask", "surface_id"];
    let pixels: Vec<_> =
        dirs.iter().map(|d| sensorlight::output::exr::read_channels(&d.join("out.exr"), &channels).unwrap()).collect();
    assert!(pixels[0] == pixels[1], "the two renders differ in their pixels");
    assert!(read(&dirs[0], "out.exr") == read(&dirs[1], "out.exr"), "same pixels, different EXR bytes");
    assert!(read(&dirs[0], "out.png") == read(&dirs[1], "out.png"), "different PNG bytes");
    let stats: Vec<serde_json::Value> =
        dirs.iter().map(|d| serde_json::from_slice(&read(d, "stats.json")).unwrap()).collect();
    assert_eq!(without_times(stats[0].clone()), without_times(stats[1].clone()));
    let keys = |bytes: Vec<u8>| {
        let text = String::from_utf8(bytes).unwrap();
        text.lines().map(|l| l.split(':').next().unwrap().to_owned()).collect::<Vec<_>>()
    };
    assert_eq!(keys(read(&dirs[0], "stats.json")), keys(read(&dirs[1], "stats.json")), "key order");
}

/// The CPU reference with one seed writes one file, byte for byte.
#[test]
fn the_same_reference_twice_writes_the_same_bytes() {
    let dir = common::scratch("outputs_reference_twice");
    for name in ["a.exr", "b.exr"] {
        let out = dir.join(name);
        let mut args = vec!["reference", CORNELL, "-o", path(&out)];
        args.extend_from_slice(&SMALL_REFERENCE);
        let run = common::sensorlight(&args);
        assert!(run.status.success(), "{}", common::stderr(&run));
    }
    assert!(std::fs::read(dir.join("a.exr")).unwrap() == std::fs::read(dir.join("b.exr")).unwrap());
    assert!(std::fs::read(dir.join("a.png")).unwrap() == std::fs::read(dir.join("b.png")).unwrap());
}

/// The EXR writer on its own, at a size with many blocks (20 tiles of 64²; the 24 × 16 render above has
/// one): the blocks are stored in increasing order, as the file says, so the bytes never depend on which
/// compression thread finished first.
#[test]
fn exr_files_store_their_blocks_in_increasing_order() {
    let dir = common::scratch("outputs_exr_order");
    let (w, h) = (300u32, 200u32);
    let pixels: Vec<glam::Vec4> = (0..w * h)
        .map(|i| {
            let x = (i.wrapping_mul(2_654_435_761) >> 8) as f32 / 16_777_216.0;
            glam::Vec4::new(x, x * 0.5, (i % w) as f32, 1.0)
        })
        .collect();
    let write = |name: &str| {
        let path = dir.join(name);
        sensorlight::output::exr::ExrImage::new(w, h).rgb("", &pixels).rgb("radiance", &pixels).write(&path).unwrap();
        path
    };
    let first = write("0.exr");
    let meta = exr::meta::MetaData::read_from_file(&first, false).unwrap();
    assert_eq!(meta.headers[0].line_order, exr::meta::attribute::LineOrder::Increasing);
    let bytes = std::fs::read(&first).unwrap();
    for i in 1..6 {
        assert!(std::fs::read(write(&format!("{i}.exr"))).unwrap() == bytes, "write {i} differs from the first");
    }
}
