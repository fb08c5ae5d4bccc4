//! The command line as a user meets it: device listing, missing drivers, renders that write real files.

mod common;

use sensorlight::output::exr;
use sensorlight::vk::{adapter, instance::Instance};

#[test]
fn devices_lists_every_device_with_its_limits() {
    let run = common::sensorlight(&["devices"]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let stdout = String::from_utf8_lossy(&run.stdout);
    let instance = Instance::new(false).unwrap();
    let adapters = adapter::enumerate(&instance).unwrap();
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

/// Renders a scene through the CLI and returns the named channels of the EXR it wrote.
fn render(scene: &str, name: &str, extra: &[&str], channels: &[&str]) -> (usize, usize, Vec<Vec<f32>>) {
    let dir = common::scratch(name);
    let out = dir.join("out.exr");
    let mut args = vec!["render", scene, "-o", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_sensorlight"))
        .args(&args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("SENSORLIGHT_VALIDATION", "1")
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", common::stderr(&run));
    assert!(dir.join("out.png").exists(), "PNG preview beside the EXR");
    exr::read_channels(&out, channels).unwrap()
}

#[test]
fn render_writes_gbuffer_aovs_of_both_cornell_boxes() {
    for (scene, name) in [
        ("scenes/cornell/cornell.toml", "render_cornell"),
        ("scenes/cornell-mcguire/cornell-mcguire.toml", "render_mcguire"),
    ] {
        let (w, h, c) =
            render(scene, name, &["--width", "40", "--height", "30"], &["albedo.R", "albedo.G", "surface_id"]);
        assert_eq!((w, h), (40, 30));
        // The red wall is on screen: some pixel has the red albedo.
        assert!(c[0].iter().zip(&c[1]).any(|(r, g)| (r - 0.63).abs() < 1e-6 && (g - 0.065).abs() < 1e-6), "{name}");
        let ids: std::collections::BTreeSet<u32> = c[2].iter().map(|&x| x as u32).collect();
        assert!(ids.len() >= 8, "{name}: {} distinct surface ids", ids.len());
    }
}

#[test]
fn zero_image_size_is_an_error() {
    let run = common::sensorlight(&[
        "render",
        common::project("scenes/cornell/cornell.toml").to_str().unwrap(),
        "-o",
        "/nonexistent/x.exr",
        "--width",
        "0",
    ]);
    assert_eq!(run.status.code(), Some(1));
    assert!(common::stderr(&run).contains("--width"), "{}", common::stderr(&run));
}
