//! `sensorlight compare` as a user meets it: a headline that weighs every lit pixel alike over the whole
//! image, the interior with silhouettes masked beside it, NaN and size mismatches refused with a non-zero
//! exit, the figures as JSON.

mod common;

use std::path::{Path, PathBuf};

use glam::Vec4;
use sensorlight::output::exr::ExrImage;

/// 8 × 2: the top row a bright emitter (surface 1), the bottom row a dim wall (surface 2).
fn reference() -> Vec<Vec4> {
    (0..16).map(|i| if i < 8 { Vec4::splat(50.0) } else { Vec4::splat(0.5) }).collect()
}

fn write(dir: &Path, name: &str, pixels: &[Vec4], ids: Option<Vec<f32>>) -> PathBuf {
    let path = dir.join(name);
    let width = 8;
    let mut image = ExrImage::new(width, pixels.len() as u32 / width).rgb("", pixels);
    if let Some(ids) = ids {
        image = image.scalar("surface_id", ids);
    }
    image.write(&path).unwrap();
    path
}

fn compare(args: &[&Path], extra: &[&str]) -> std::process::Output {
    let mut all: Vec<&str> = vec!["compare"];
    all.extend(args.iter().map(|p| p.to_str().unwrap()));
    all.extend_from_slice(extra);
    common::sensorlight(&all)
}

/// The wall is 10 % off, the emitter exact: the headline is the per-pixel RMSE (0.1 over half the lit
/// pixels: √0.005 ≈ 0.0707), not the emitter-dominated L2 ratio, which is shown beside it.
#[test]
fn the_headline_is_the_per_pixel_relative_rmse() {
    let dir = common::scratch("compare_headline");
    let b = write(&dir, "ref.exr", &reference(), None);
    let judged: Vec<Vec4> = reference().iter().map(|&p| if p.x < 1.0 { p * 1.1 } else { p }).collect();
    let a = write(&dir, "a.exr", &judged, None);
    let json = dir.join("figures.json");
    let run = compare(&[&a, &b], &["--json", json.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let headline = stdout.lines().next().unwrap();
    assert!(
        headline.starts_with("whole image (nothing masked): relative RMSE 0.0707 ")
            && headline.contains("16 lit pixels"),
        "{stdout}"
    );
    assert!(stdout.contains("interior: relative RMSE 0.0707 "), "nothing to mask here: {stdout}");
    assert!(stdout.contains("mean absolute relative error 0.0500") && stdout.contains("L2 ratio 0.0010"), "{stdout}");
    assert!(stdout.contains("no surface_id channel"), "{stdout}");
    let figures: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(figures["image"], a.to_str().unwrap());
    assert!(figures["lit_fraction"].is_number(), "{figures}");
    for part in ["whole", "interior"] {
        let f = &figures[part];
        assert!((f["relative_rmse"].as_f64().unwrap() - 0.005f64.sqrt()).abs() < 1e-6, "{part}: {figures}");
        assert_eq!(f["lit_pixels"], 16);
        assert_eq!(f["masked_pixels"], 0);
        for key in ["mean_abs_relative_error", "relative_bias", "l2_ratio", "lit_threshold"] {
            assert!(f[key].is_number(), "{part}: {key} missing: {figures}");
        }
    }
}

/// With a surface_id channel, the interior masks the row on either side of the edge between the two
/// surfaces: a 3 × 3 neighbourhood there holds both ids. Both rows are the edge here, so take 8 × 4 with the
/// edge in the middle: rows 1 and 2 masked (16 pixels), and their large error does not count there; the
/// whole image counts it (16 of 32 pixels 200 % off: 1.4142).
#[test]
fn silhouettes_are_masked_and_counted() {
    let dir = common::scratch("compare_silhouettes");
    let b_pixels: Vec<Vec4> = (0..32).map(|i| if i < 16 { Vec4::splat(5.0) } else { Vec4::splat(1.0) }).collect();
    let ids: Vec<f32> = (0..32).map(|i| if i < 16 { 1.0 } else { 2.0 }).collect();
    let a_pixels: Vec<Vec4> =
        b_pixels.iter().enumerate().map(|(i, &p)| if (8..24).contains(&i) { p * 3.0 } else { p }).collect();
    let b = write(&dir, "ref.exr", &b_pixels, None);
    let a = write(&dir, "a.exr", &a_pixels, Some(ids));
    let run = compare(&[&a, &b], &[]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{}", common::stderr(&run));
    assert!(
        stdout.starts_with("whole image (nothing masked): relative RMSE 1.4142 (per pixel, luminance, over 32 lit"),
        "{stdout}"
    );
    assert!(stdout.contains("interior: relative RMSE 0.0000 ") && stdout.contains("16 lit pixels of 32"), "{stdout}");
    assert!(stdout.contains("16 silhouette pixel(s) masked"), "{stdout}");
}

/// NaN or infinite values in either image, or two sizes, are errors with a clear message and exit 1,
/// however the rest of the image compares; nothing is written to --json.
#[test]
fn nan_inf_and_size_mismatches_are_errors() {
    let dir = common::scratch("compare_errors");
    let good = write(&dir, "good.exr", &reference(), None);
    let nan = write(&dir, "nan.exr", &[Vec4::splat(f32::NAN); 16], None);
    let mut some_inf = reference();
    some_inf[3] = Vec4::new(f32::INFINITY, 1.0, 1.0, 1.0);
    some_inf[12] = Vec4::splat(f32::NAN);
    let inf = write(&dir, "inf.exr", &some_inf, None);
    let small = dir.join("small.exr");
    ExrImage::new(4, 2).rgb("", &reference()[..8]).write(&small).unwrap();
    let json = dir.join("figures.json");
    let json = json.to_str().unwrap();
    let cases: [(&Path, &Path, &[&str]); 4] = [
        (&good, &nan, &["nan.exr: 16 NaN and 0 infinite pixel(s)", "good.exr: no NaN or infinite pixel"]),
        (&nan, &good, &["nan.exr: 16 NaN"]),
        (&inf, &good, &["inf.exr: 1 NaN and 1 infinite pixel(s), the first at x 3, y 0"]),
        (&good, &small, &["good.exr is 8x2 but", "small.exr is 4x2"]),
    ];
    for (a, b, expected) in cases {
        let args = ["compare", a.to_str().unwrap(), b.to_str().unwrap(), "--json", json];
        let stderr = common::expect_failure(&args, expected[0]);
        for piece in expected {
            assert!(stderr.contains(piece), "{args:?}: lacks {piece:?}: {stderr}");
        }
        assert_eq!(common::sensorlight(&args).status.code(), Some(1));
        assert!(!Path::new(json).exists(), "no figures written for a failed comparison");
    }
    let black = write(&dir, "black.exr", &[Vec4::ZERO; 16], None);
    common::expect_failure(&["compare", good.to_str().unwrap(), black.to_str().unwrap()], "no lit pixel");
    common::expect_failure(&["compare", good.to_str().unwrap(), "missing.exr"], "missing.exr");
}
