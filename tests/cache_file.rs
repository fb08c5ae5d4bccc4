//! The radiance cache as a file (issue 41, item 1): `sensorlight cache` writes it, `render --cache` reads it
//! and renders the same bytes as a render that solves its own; a file of another scene, other settings, a
//! damaged or a foreign file is refused naming what is wrong, and nothing is written.

mod common;

use std::path::Path;

const SCENE: &str = "scenes/cornell/cornell.toml";
/// Small and quick: the cache depends on the sensor size, so every command below is given the same.
const FLAGS: [&str; 4] = ["--sensor-size", "16", "--strategy", "layered"];

fn run(args: &[&str]) -> std::process::Output {
    let mut all = args.to_vec();
    all.extend_from_slice(&FLAGS);
    common::sensorlight(&all)
}

fn render(out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["render", SCENE, "-o", out.to_str().unwrap(), "--width", "40", "--height", "30"];
    args.extend_from_slice(extra);
    run(&args)
}

#[test]
fn a_render_from_the_cache_file_equals_the_render_that_solves_its_own() {
    let dir = common::scratch("cache_file_equal");
    let file = dir.join("cornell.slc");
    let made = run(&["cache", SCENE, "-o", file.to_str().unwrap()]);
    assert!(made.status.success(), "{}", common::stderr(&made));
    let said = common::stderr(&made);
    assert!(said.contains("bounces") && said.contains("entries"), "{said}");
    assert!(!said.contains("pixels resolved"), "the cache has no pixels to resolve: {said}");

    let (alone, cached) = (dir.join("alone.exr"), dir.join("cached.exr"));
    let a = render(&alone, &[]);
    assert!(a.status.success(), "{}", common::stderr(&a));
    let b = render(&cached, &["--cache", file.to_str().unwrap()]);
    assert!(b.status.success(), "{}", common::stderr(&b));
    let (a, b) = (std::fs::read(&alone).unwrap(), std::fs::read(&cached).unwrap());
    assert!(a == b, "the EXR rendered from the cache file differs from the one that solved its own");
    let png = |p: &Path| std::fs::read(p.with_extension("png")).unwrap();
    assert!(png(&alone) == png(&cached), "the PNGs differ");
}

#[test]
fn a_cache_of_other_settings_another_scene_or_a_damaged_file_is_refused() {
    let dir = common::scratch("cache_file_refused");
    let file = dir.join("cornell.slc");
    let made = run(&["cache", SCENE, "-o", file.to_str().unwrap()]);
    assert!(made.status.success(), "{}", common::stderr(&made));
    let out = dir.join("out.exr");
    let cache = file.to_str().unwrap();
    let refused = |extra: &[&str], expected: &str| {
        let run = render(&out, extra);
        let stderr = common::stderr(&run);
        assert_eq!(run.status.code(), Some(1), "{extra:?}: {stderr}");
        assert!(stderr.contains(expected), "{extra:?}: stderr lacks {expected:?}: {stderr}");
        assert!(!out.exists() && !out.with_extension("png").exists(), "{extra:?} wrote an output");
    };
    refused(&["--cache", cache, "--cache-resolution", "8"], "--cache-resolution (the cache's: 16, this render's: 8)");
    // A sun adds its disc (a triangle and its material) besides itself.
    refused(&["--cache", cache, "--sun", "0,1,0"], "the materials or their textures; the sun");
    let mut bytes = std::fs::read(&file).unwrap();
    let damaged = dir.join("damaged.slc");
    bytes.truncate(bytes.len() - 100);
    std::fs::write(&damaged, &bytes).unwrap();
    refused(&["--cache", damaged.to_str().unwrap()], "is truncated or damaged");
    refused(&["--cache", SCENE], "is not a sensorlight radiance cache");
    refused(&["--cache", dir.join("missing.slc").to_str().unwrap()], "cannot read it");

    // Another scene: what differs is named, here its geometry and materials.
    let other = run(&["render", "scenes/small-light/small-light.toml", "-o", out.to_str().unwrap(), "--cache", cache]);
    let stderr = common::stderr(&other);
    assert_eq!(other.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("the geometry; the materials or their textures"), "{stderr}");

    // A cache is for global illumination; and it never overwrites its scene.
    let none = dir.join("none.slc");
    let direct = run(&["cache", SCENE, "-o", none.to_str().unwrap(), "--bounces", "0"]);
    assert!(common::stderr(&direct).contains("needs no radiance cache"), "{}", common::stderr(&direct));
    assert!(!none.exists());
    let onto = run(&["cache", SCENE, "-o", SCENE]);
    assert!(common::stderr(&onto).contains("would overwrite the input"), "{}", common::stderr(&onto));
}
