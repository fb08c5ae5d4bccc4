//! Shared test helpers: a validated GPU, the CLI binary, scratch directories.
#![allow(dead_code)] // each test binary uses a different subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Arc;

use sensorlight::vk::{Device, DeviceOptions};

/// Runs `work` on the default device with the Khronos validation layer on, then destroys the device and
/// fails the test if the layer reported anything (including objects left undestroyed).
pub fn gpu<R>(work: impl FnOnce(&Arc<Device>) -> R) -> R {
    let device = Device::new(&DeviceOptions { validation: true, device_index: None })
        .expect("tests need a Vulkan device and the validation layer (see README)");
    let log = device.validation_log().clone();
    let result = work(&device);
    drop(device);
    let messages = log.messages();
    assert!(messages.is_empty(), "validation layer reported {} message(s):\n{}", messages.len(), messages.join("\n"));
    result
}

/// A fresh, empty directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the `sensorlight` binary with validation on.
pub fn sensorlight(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sensorlight"))
        .args(args)
        .env("SENSORLIGHT_VALIDATION", "1")
        .output()
        .expect("cannot run sensorlight")
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn project(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

use glam::Vec3;
use sensorlight::scene::obj::{Material, ObjGroup};
use sensorlight::scene::{Camera, ImageSize, Mesh, RenderDefaults, Scene};

/// An axis-aligned rectangle as two triangles, wound so that its front faces `facing`.
pub fn rect(center: Vec3, half_u: Vec3, half_v: Vec3, facing: Vec3) -> Vec<[Vec3; 3]> {
    let c = [center - half_u - half_v, center + half_u - half_v, center + half_u + half_v, center - half_u + half_v];
    let flip = half_u.cross(half_v).dot(facing) < 0.0;
    let tris = vec![[c[0], c[1], c[2]], [c[0], c[2], c[3]]];
    if flip { tris.into_iter().map(|[a, b, c]| [a, c, b]).collect() } else { tris }
}

pub fn material(name: &str, kd: f32, ke: f32) -> Material {
    Material { name: name.into(), kd: Vec3::splat(kd), ke: Vec3::splat(ke) }
}

/// A scene built in code: `groups` are (name, material index, triangles).
pub fn scene(
    groups: Vec<(&str, usize, Vec<[Vec3; 3]>)>,
    materials: Vec<Material>,
    camera: Camera,
    size: (u32, u32),
) -> Scene {
    let groups: Vec<ObjGroup> = groups
        .into_iter()
        .map(|(name, material, triangles)| ObjGroup { name: name.into(), material, triangles })
        .collect();
    let mut warnings = Vec::new();
    Scene {
        path: "(built in a test)".into(),
        mesh: Mesh::new(&groups, materials, &mut warnings).unwrap(),
        camera,
        image: ImageSize { width: size.0, height: size.1 },
        render: RenderDefaults::default(),
        warnings,
    }
}

/// A closed cube of side 2 centred at the origin, every face emitting `ke` towards the inside, camera inside.
pub fn furnace(ke: f32) -> Scene {
    let mut tris = Vec::new();
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        let (u, v) = (axis.any_orthonormal_pair().0, axis.any_orthonormal_pair().1);
        for sign in [1.0, -1.0] {
            tris.extend(rect(axis * sign, u, v, -axis * sign));
        }
    }
    let camera = Camera::look_at(Vec3::new(0.3, 0.2, 0.5), Vec3::new(-0.4, -0.5, -1.0), Vec3::Y, 90.0).unwrap();
    scene(vec![("box", 0, tris)], vec![material("glow", 0.5, ke)], camera, (24, 24))
}

/// A closed-back room (open towards the camera) with a large ceiling light and a block: an accuracy test
/// scene whose light is large enough that the CPU reference converges quickly.
pub fn lightbox(size: (u32, u32)) -> Scene {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let c = Vec3::new(0.0, 1.0, 0.0);
    let mut groups = vec![
        ("floor", 0, rect(Vec3::ZERO, x, z, y)),
        ("ceiling", 0, rect(2.0 * y, x, z, -y)),
        ("back", 0, rect(c - z, x, y, z)),
        ("left", 1, rect(c - x, z, y, x)),
        ("right", 2, rect(c + x, z, y, -x)),
        ("light", 3, rect(1.99 * y, x * 0.5, z * 0.5, -y)),
    ];
    let (center, half) = (Vec3::new(0.3, 0.35, -0.2), Vec3::new(0.25, 0.35, 0.25));
    for (n, u, v) in [(x, z, y), (-x, z, y), (z, x, y), (-z, x, y), (y, x, z)] {
        groups.push(("block", 0, rect(center + n * half, u * half, v * half, n)));
    }
    let camera = Camera::look_at(Vec3::new(0.0, 1.0, 3.4), c, y, 40.0).unwrap();
    let materials = vec![
        Material { name: "white".into(), kd: Vec3::splat(0.7), ke: Vec3::ZERO },
        Material { name: "red".into(), kd: Vec3::new(0.7, 0.1, 0.1), ke: Vec3::ZERO },
        Material { name: "green".into(), kd: Vec3::new(0.1, 0.7, 0.1), ke: Vec3::ZERO },
        Material { name: "light".into(), kd: Vec3::splat(0.5), ke: Vec3::splat(4.0) },
    ];
    scene(groups, materials, camera, size)
}

/// Parameters that sense every pixel and do not filter: the GPU's R at every pixel, as sensed.
pub fn every_pixel(
    sensor: sensorlight::sensors::SensorKind,
    rd: u32,
    epsilon: f32,
) -> sensorlight::params::RenderParams {
    sensorlight::params::RenderParams {
        estimator: sensorlight::params::EstimatorParams { sensor, epsilon, background: Vec3::ZERO },
        sensor_size: rd,
        tile: 1,
        dradiance: 0.0,
        filter_radius: 0,
        exposure: 0.0,
    }
}

/// Renders `scene` on a validated GPU.
pub fn render(
    scene: &Scene,
    params: &sensorlight::params::RenderParams,
    budget: Option<u64>,
) -> sensorlight::renderer::RenderOutput {
    gpu(|device| {
        let mut renderer =
            sensorlight::renderer::Renderer::new(device, scene, params.estimator.sensor, params.sensor_size, budget)
                .unwrap();
        renderer.render(scene, scene.image, params, &sensorlight::renderer::Quiet).unwrap()
    })
}
