//! Frames of a camera path (issue 41, item 3): `render --frames A..B` writes OUT.####.exr, one radiance cache
//! for them all; a frame rendered alone, or from a cache file, equals the same frame of the sequence byte
//! for byte; frames outside the path, a scene without one and bad ranges are refused.

mod common;

use std::path::Path;

const SCENE: &str = "scenes/cornell/fly.toml";
const FLAGS: [&str; 8] = ["--width", "40", "--height", "40", "--sensor-size", "16", "--strategy", "layered"];

fn render(out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["render", SCENE, "-o", out.to_str().unwrap()];
    args.extend_from_slice(&FLAGS);
    args.extend_from_slice(extra);
    common::sensorlight(&args)
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn a_frame_alone_or_from_the_cache_file_equals_the_same_frame_of_the_sequence() {
    let dir = common::scratch("frames_equal");
    let run = render(&dir.join("seq.exr"), &["--frames", "11..13"]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    for k in 11..=13 {
        for ext in ["exr", "png"] {
            assert!(dir.join(format!("seq.{k:04}.{ext}")).is_file(), "frame {k}'s {ext}");
        }
    }
    assert!(bytes(&dir.join("seq.0011.exr")) != bytes(&dir.join("seq.0013.exr")), "the camera moves");
    let run = render(&dir.join("one.exr"), &["--frame", "12"]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    assert!(bytes(&dir.join("one.0012.exr")) == bytes(&dir.join("seq.0012.exr")), "frame 12 alone differs");
    assert!(bytes(&dir.join("one.0012.png")) == bytes(&dir.join("seq.0012.png")), "frame 12's PNG differs");

    let cache = dir.join("fly.slc");
    let mut args = vec!["cache", SCENE, "-o", cache.to_str().unwrap()];
    args.extend_from_slice(&FLAGS);
    let run = common::sensorlight(&args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let run = render(&dir.join("cached.exr"), &["--frame", "12", "--cache", cache.to_str().unwrap()]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    assert!(bytes(&dir.join("cached.0012.exr")) == bytes(&dir.join("seq.0012.exr")), "from the cache file, it differs");
}

#[test]
fn frames_outside_the_path_or_without_one_are_refused() {
    let dir = common::scratch("frames_refused");
    let out = dir.join("out.exr");
    for (extra, expected) in [
        (&["--frame", "25"][..], "frame 25 is after the path's end: its last key is frame 24 (at 12 fps)"),
        (&["--frames", "3..1"][..], "the first frame comes after the last"),
        (&["--frames", "1-3"][..], "expected A..B"),
        (&["--frames", "0..1", "--image-tile", "1/2"][..], "cannot be used with"),
    ] {
        let run = render(&out, extra);
        let stderr = common::stderr(&run);
        assert!(matches!(run.status.code(), Some(1 | 2)) && stderr.contains(expected), "{extra:?}: {stderr}");
    }
    let run =
        common::sensorlight(&["render", "scenes/cornell/cornell.toml", "-o", out.to_str().unwrap(), "--frame", "0"]);
    assert!(common::stderr(&run).contains("has no [path]"), "{}", common::stderr(&run));
    assert!(std::fs::read_dir(&dir).unwrap().next().is_none(), "a refused render wrote something");
}

/// `--write-scene` writes the camera path too: the written scene renders the path's frames as the original.
#[test]
fn a_written_scene_keeps_its_camera_path() {
    let dir = common::scratch("frames_write_scene");
    let written = dir.join("written.toml");
    let run = render(&dir.join("a.exr"), &["--frame", "5", "--write-scene", written.to_str().unwrap()]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let text = std::fs::read_to_string(&written).unwrap();
    assert!(text.contains("[path]") && text.matches("[[path.key]]").count() == 3, "{text}");
    let out = dir.join("b.exr");
    let mut args = vec!["render", written.to_str().unwrap(), "-o", out.to_str().unwrap(), "--frame", "5"];
    args.extend_from_slice(&FLAGS);
    let again = common::sensorlight(&args);
    assert!(again.status.success(), "{}", common::stderr(&again));
    assert!(bytes(&dir.join("a.0005.exr")) == bytes(&dir.join("b.0005.exr")), "the written scene's frame 5 differs");
}
