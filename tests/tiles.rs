//! A render split into tiles (issue 41, item 2): `render --image-tile I/N` and `sensorlight assemble` give
//! the single render's EXR (AOVs too) and PNG byte for byte; missing, duplicate, foreign and overlapping
//! tiles are refused naming them, and nothing is written.

mod common;

use std::path::{Path, PathBuf};

const SCENE: &str = "scenes/cornell/cornell.toml";
const FLAGS: [&str; 8] = ["--width", "48", "--height", "36", "--sensor-size", "16", "--strategy", "layered"];

fn render(out: &Path, extra: &[&str]) {
    let mut args = vec!["render", SCENE, "-o", out.to_str().unwrap()];
    args.extend_from_slice(&FLAGS);
    args.extend_from_slice(extra);
    let run = common::sensorlight(&args);
    assert!(run.status.success(), "{args:?}: {}", common::stderr(&run));
}

/// Renders the N tiles of the scene into `dir`, each with `extra`; returns their paths.
fn tiles(dir: &Path, n: u32, extra: &[&str]) -> Vec<PathBuf> {
    (1..=n)
        .map(|i| {
            let path = dir.join(format!("tile{i}.exr"));
            let spec = format!("{i}/{n}");
            let mut args = vec!["--image-tile", spec.as_str()];
            args.extend_from_slice(extra);
            render(&path, &args);
            assert!(!path.with_extension("png").exists(), "a tile wrote a PNG");
            path
        })
        .collect()
}

fn assemble(tiles: &[PathBuf], out: &Path) -> std::process::Output {
    let mut args = vec!["assemble".to_owned()];
    args.extend(tiles.iter().map(|t| t.display().to_string()));
    args.extend(["-o".to_owned(), out.display().to_string()]);
    common::sensorlight(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

fn same_file(a: &Path, b: &Path) -> bool {
    std::fs::read(a).unwrap() == std::fs::read(b).unwrap()
}

#[test]
fn joined_tiles_equal_the_single_render_byte_for_byte() {
    for (name, n, extra) in [("plain", 4, &[][..]), ("aovs", 3, &["--aovs"][..])] {
        let dir = common::scratch(&format!("tiles_equal_{name}"));
        let whole = dir.join("whole.exr");
        render(&whole, extra);
        let parts = tiles(&dir, n, extra);
        let joined = dir.join("joined.exr");
        let run = assemble(&parts, &joined);
        assert!(run.status.success(), "{}", common::stderr(&run));
        assert!(same_file(&whole, &joined), "{name}: the joined EXR differs from the single render's");
        let png = |p: &Path| p.with_extension("png");
        assert!(same_file(&png(&whole), &png(&joined)), "{name}: the joined PNG differs");
    }
}

#[test]
fn missing_duplicate_foreign_and_overlapping_tiles_are_refused() {
    let dir = common::scratch("tiles_refused");
    let parts = tiles(&dir, 3, &[]);
    let out = dir.join("joined.exr");
    let refused = |tiles: &[PathBuf], expected: &str| {
        let run = assemble(tiles, &out);
        let stderr = common::stderr(&run);
        assert_eq!(run.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains(expected), "stderr lacks {expected:?}: {stderr}");
        assert!(!out.exists() && !out.with_extension("png").exists(), "assemble wrote {}", out.display());
    };
    refused(&parts[..2], "missing tile(s) 3/3 of the 3");
    refused(&[parts[0].clone(), parts[1].clone(), parts[1].clone(), parts[2].clone()], "tile 2/3 is given twice");
    // Another render's tile (another setting), another count of tiles, an image that is no tile.
    let other = dir.join("other");
    std::fs::create_dir_all(&other).unwrap();
    let foreign = tiles(&other, 3, &["--dradiance", "0.1"]);
    refused(&[parts[0].clone(), parts[1].clone(), foreign[2].clone()], "are tiles of different renders");
    // The same render but --aovs: the joined file would not be one render's.
    let with_aovs = other.join("aovs.exr");
    render(&with_aovs, &["--image-tile", "3/3", "--aovs"]);
    refused(&[parts[0].clone(), parts[1].clone(), with_aovs], "are tiles of different renders");
    let whole = dir.join("whole.exr");
    render(&whole, &[]);
    refused(std::slice::from_ref(&whole), "not a tile of `render --image-tile`");
    // A tile whose pixels are not where its number puts them: one that claims to be another's.
    let moved = dir.join("moved.exr");
    let mut bytes = std::fs::read(&parts[2]).unwrap();
    let at = bytes.windows(3).position(|w| w == b"3/3").expect("the tile's number in its header");
    bytes[at] = b'2';
    std::fs::write(&moved, &bytes).unwrap();
    refused(&[parts[0].clone(), moved, parts[2].clone()], "it overlaps another");

    for (spec, expected) in
        [("0/4", "runs from 1"), ("5/4", "runs from 1"), ("a/b", "expected I/N"), ("40/40", "at least 40 pixels high")]
    {
        let run = common::sensorlight(&[
            "render",
            SCENE,
            "-o",
            out.to_str().unwrap(),
            "--height",
            "36",
            "--image-tile",
            spec,
        ]);
        let stderr = common::stderr(&run);
        assert!(matches!(run.status.code(), Some(1 | 2)) && stderr.contains(expected), "{spec}: {stderr}");
    }
    let png = dir.join("tile.png");
    common::expect_failure(
        &["render", SCENE, "-o", png.to_str().unwrap(), "--image-tile", "1/2"],
        "--image-tile writes an EXR",
    );
}
