//! What the commands write, as a user meets it: the same command writes the same bytes.

mod common;

use std::path::{Path, PathBuf};

const CORNELL: &str = "scenes/cornell/cornell.toml";
/// A small, fast CPU reference of the Cornell box.
const SMALL_REFERENCE: [&str; 6] = ["--width", "24", "--height", "16", "--samples", "8"];

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn without_times(mut stats: serde_json::Value) -> serde_json::Value {
    for key in ["total_seconds", "gpu_sensor_seconds", "gpu_other_seconds", "host_seconds", "sensor_time_ms"] {
        assert!(stats.get(key).is_some(), "{key} missing");
        stats[key] = serde_json::Value::Null;
    }
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
