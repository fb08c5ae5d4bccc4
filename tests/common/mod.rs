//! Shared test helpers: a validated GPU, the CLI binary, scratch directories.
#![allow(dead_code)] // each test binary uses a different subset

pub mod gltf;
pub mod hall;
pub mod meshes;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Arc;

use sensorlight::vk::{Device, DeviceOptions};

/// Runs `work` on the default device with the Khronos validation layer on, then destroys the device and
/// fails the test if the layer reported anything (including objects left undestroyed).
pub fn gpu<R>(work: impl FnOnce(&Arc<Device>) -> R) -> R {
    let options = DeviceOptions {
        validation: true,
        device_index: None,
        requirements: sensorlight::passes::requirements(),
        window: None,
    };
    let device = Device::new(&options).expect("tests need a Vulkan device and the validation layer (see README)");
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

/// The `sensorlight` binary with validation on, run in the project root, its strategy cache kept apart
/// from the user's.
pub fn command() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_sensorlight"));
    command
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("SENSORLIGHT_VALIDATION", "1")
        .env("SENSORLIGHT_CACHE_DIR", Path::new(env!("CARGO_TARGET_TMPDIR")).join("strategy-cache"));
    command
}

/// Runs the `sensorlight` binary (see [`command`]).
pub fn sensorlight(args: &[&str]) -> Output {
    command().args(args).output().expect("cannot run sensorlight")
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Runs `sensorlight args` and checks that it fails the way a user error should: exit code 1 (2 for a flag
/// that does not parse, as clap reports it), a message containing `expected`, no panic. Returns stderr.
pub fn expect_failure(args: &[&str], expected: &str) -> String {
    let run = sensorlight(args);
    let stderr = stderr(&run);
    assert!(matches!(run.status.code(), Some(1 | 2)), "{args:?}: exit code {:?}; stderr: {stderr}", run.status.code());
    assert!(stderr.contains(expected), "{args:?}: stderr lacks {expected:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    stderr
}

pub fn project(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

use glam::{Vec3, Vec4};
use sensorlight::metrics::compare::{Comparison, Picture, compare};
use sensorlight::params::{
    Antialiasing, EstimatorKind, EstimatorParams, FrameParams, Indirect, Overrides, RenderParams,
};
use sensorlight::reference::integrator::Integrator;
use sensorlight::renderer::{CacheConfig, Quiet, RenderOutput, Renderer};
pub use sensorlight::scene::builtin::{lightbox as builtin_lightbox, rect};
use sensorlight::scene::material::Material;
use sensorlight::scene::{Camera, ImageSize, Scene};
use sensorlight::sensors::SensorKind;
use sensorlight::strategy::StrategyKind;

pub fn material(name: &str, kd: f32, ke: f32) -> Material {
    Material::new(name, Vec3::splat(kd), Vec3::splat(ke))
}

/// A scene built in code: `groups` are (name, material index, triangles).
pub fn scene(
    groups: Vec<(&str, usize, Vec<[Vec3; 3]>)>,
    materials: Vec<Material>,
    camera: Camera,
    size: (u32, u32),
) -> Scene {
    sensorlight::scene::builtin::from_groups(groups, materials, camera, ImageSize { width: size.0, height: size.1 })
}

/// Two rooms under one floor and one ceiling (x in [-2, 2], y in [0, 2], z in [-1, 1]), divided at x = 0 by
/// a wall of `thickness` (0: one quad), a light on the ceiling over x > 0 only; the camera in the dark room,
/// `size` pixels.
pub fn two_rooms(thickness: f32, size: (u32, u32)) -> Scene {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let c = y;
    let mut groups = two_rooms_shell();
    groups.push(("light", 1, rect(Vec3::new(1.0, 1.99, 0.0), x * 0.3, z * 0.3, -y)));
    if thickness == 0.0 {
        groups.push(("wall", 0, rect(c, z, y, x)));
    } else {
        for n in [x, -x] {
            groups.push(("wall", 0, rect(c + n * (thickness / 2.0), z, y, n)));
        }
    }
    let camera = Camera::look_at(Vec3::new(-1.8, 1.5, 0.8), Vec3::new(0.0, 0.3, -0.3), y, 70.0).unwrap();
    let materials = vec![material("white", 0.8, 0.0), material("light", 0.8, 50.0)];
    scene(groups, materials, camera, size)
}

/// The shell around [`two_rooms`]: floor, ceiling and four walls facing in (x in [-2, 2], y in [0, 2], z in
/// [-1, 1]), material 0, no divider.
pub fn two_rooms_shell() -> Vec<(&'static str, usize, Vec<[Vec3; 3]>)> {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let c = y;
    vec![
        ("floor", 0, rect(Vec3::ZERO, x * 2.0, z, y)),
        ("ceiling", 0, rect(2.0 * y, x * 2.0, z, -y)),
        ("back", 0, rect(c - z, x * 2.0, y, z)),
        ("front", 0, rect(c + z, x * 2.0, y, -z)),
        ("left", 0, rect(c - 2.0 * x, z, y, x)),
        ("right", 0, rect(c + 2.0 * x, z, y, -x)),
    ]
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

/// A small bright light (0.1 m square at 2 m, Ke 2000, facing down) over a 0.3 m square occluder at 0.6 m,
/// above a 4 × 4 m floor (Kd 0.5), seen from above the shadow: the case a cosine-only oracle cannot check.
pub fn small_light(size: (u32, u32)) -> Scene {
    let groups = vec![
        ("floor", 0, rect(Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 2.0, Vec3::Y)),
        ("occluder", 0, rect(Vec3::new(0.25, 0.6, 0.0), Vec3::X * 0.15, Vec3::Z * 0.15, Vec3::Y)),
        ("light", 1, rect(Vec3::new(0.0, 2.0, 0.0), Vec3::X * 0.05, Vec3::Z * 0.05, -Vec3::Y)),
    ];
    let camera = Camera::look_at(Vec3::new(1.4, 2.4, 1.2), Vec3::new(0.3, 0.0, 0.0), Vec3::Y, 40.0).unwrap();
    scene(groups, vec![material("grey", 0.5, 0.0), material("light", 0.0, 2000.0)], camera, size)
}

/// Thin geometry: a fence of 12 bars 1.2 cm wide (a third of a pixel at 96 × 64) in front of a wall, on a
/// floor, under a 0.4 m square light (Ke 10) that the camera, 10 cm below its plane, sees nearly edge-on (a
/// sliver a third of a pixel tall): what pixel centres miss.
pub fn fence(size: (u32, u32)) -> Scene {
    let mut bars = Vec::new();
    for k in 0..12 {
        let x = -0.55 + 0.1 * k as f32;
        bars.extend(rect(Vec3::new(x, 0.4, 0.0), Vec3::X * 0.006, Vec3::Y * 0.4, Vec3::Z));
    }
    let groups = vec![
        ("floor", 0, rect(Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 2.0, Vec3::Y)),
        ("wall", 0, rect(Vec3::new(0.0, 1.0, -1.0), Vec3::X * 2.0, Vec3::Y * 1.0, Vec3::Z)),
        ("fence", 1, bars),
        ("light", 2, rect(Vec3::new(0.0, 1.5, 0.0), Vec3::X * 0.2, Vec3::Z * 0.2, -Vec3::Y)),
    ];
    let camera = Camera::look_at(Vec3::new(0.0, 1.4, 3.0), Vec3::new(0.0, 0.7, -0.5), Vec3::Y, 50.0).unwrap();
    let materials = vec![material("grey", 0.5, 0.0), material("bars", 0.8, 0.0), material("light", 0.0, 10.0)];
    scene(groups, materials, camera, size)
}

/// A sphere of flat facets (12 stacks, 22.5° apart: one surface whose normals jump at every edge) and a box
/// on a floor beside a wall, under a 0.5 m light: R curves across the facets and breaks at their edges.
pub fn sphere_by_a_wall(size: (u32, u32)) -> Scene {
    sphere_by_a_wall_of(size, 12)
}

/// [`sphere_by_a_wall`] with a sphere of `stacks` stacks (`4 · stacks · (stacks − 1)` triangles).
pub fn sphere_by_a_wall_of(size: (u32, u32), stacks: usize) -> Scene {
    let groups = vec![
        ("floor", 0, rect(Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 2.0, Vec3::Y)),
        ("wall", 0, rect(Vec3::new(0.0, 1.0, -1.0), Vec3::X * 2.0, Vec3::Y, Vec3::Z)),
        ("sphere", 1, meshes::sphere(Vec3::new(-0.3, 0.4, -0.5), 0.4, stacks)),
        ("box", 1, rect(Vec3::new(0.6, 0.3, -0.6), Vec3::X * 0.2, Vec3::Y * 0.3, Vec3::Z)),
        ("light", 2, rect(Vec3::new(0.3, 1.8, 0.2), Vec3::X * 0.25, Vec3::Z * 0.25, -Vec3::Y)),
    ];
    let camera = Camera::look_at(Vec3::new(0.4, 1.2, 2.2), Vec3::new(0.0, 0.4, -0.6), Vec3::Y, 50.0).unwrap();
    let materials = vec![material("grey", 0.6, 0.0), material("blue", 0.5, 0.0), material("light", 0.0, 20.0)];
    scene(groups, materials, camera, size)
}

/// A wall lit at a grazing angle by a light strip at its foot, 5 cm out, with a post between: R peaks and
/// falls off steeply across the wall, and the post's shadow crosses it.
pub fn grazing_wall(size: (u32, u32)) -> Scene {
    let groups = vec![
        ("wall", 0, rect(Vec3::new(0.0, 1.0, 0.0), Vec3::X * 1.5, Vec3::Y, Vec3::Z)),
        ("floor", 0, rect(Vec3::new(0.0, 0.0, 1.0), Vec3::X * 1.5, Vec3::Z, Vec3::Y)),
        ("post", 0, rect(Vec3::new(0.2, 0.4, 0.1), Vec3::X * 0.03, Vec3::Y * 0.4, Vec3::Z)),
        ("light", 1, rect(Vec3::new(0.0, 0.02, 0.05), Vec3::X * 1.0, Vec3::Z * 0.02, Vec3::Y)),
    ];
    let camera = Camera::look_at(Vec3::new(0.3, 1.0, 2.5), Vec3::new(0.0, 0.8, 0.0), Vec3::Y, 50.0).unwrap();
    scene(groups, vec![material("white", 0.7, 0.0), material("light", 0.0, 10.0)], camera, size)
}

/// `scene` on the GPU and its G-buffer at `size` (near plane 1e-3), rasterised and read back.
pub fn raster_gbuffer(
    device: &Arc<Device>,
    scene: &Scene,
    size: ImageSize,
) -> (sensorlight::gpu_scene::GpuScene, sensorlight::passes::gbuffer::GBuffer, sensorlight::gbuffer::GBufferData) {
    let gpu_scene = sensorlight::gpu_scene::GpuScene::upload(device, scene, None, None).unwrap();
    let gbuffer = sensorlight::passes::gbuffer::GBufferPass::new(device, &gpu_scene)
        .unwrap()
        .render(device, &gpu_scene, &scene.camera, size, 1e-3)
        .unwrap();
    let g = gbuffer.read_back(device).unwrap();
    (gpu_scene, gbuffer, g)
}

/// 16 points in each pixel of an image of `size`, pixel by pixel: a 4 × 4 grid over its square (the
/// G-buffer shader's grid), in continuous pixel coordinates.
pub fn pixel_grid(size: ImageSize) -> Vec<glam::Vec2> {
    let (w, h) = (size.width as usize, size.height as usize);
    (0..w * h)
        .flat_map(|i| {
            let pixel = glam::Vec2::new((i % w) as f32, (i / w) as f32);
            (0..16).map(move |k| pixel + (glam::Vec2::new((k % 4) as f32, (k / 4) as f32) + 0.5) / 4.0)
        })
        .collect()
}

/// The built-in lightbox (see `scene::builtin`) at `size`.
pub fn lightbox(size: (u32, u32)) -> Scene {
    builtin_lightbox(ImageSize { width: size.0, height: size.1 })
}

/// What a test renders with: the estimator, the sensor map size and the per-render parameters.
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    pub kind: EstimatorKind,
    pub estimator: EstimatorParams,
    pub rd: u32,
    pub frame: FrameParams,
    /// The radiance cache, for global illumination.
    pub cache: Option<CacheConfig>,
}

impl Setup {
    /// What `sensorlight render` renders with at the resolved parameters `p`.
    pub fn of(p: &RenderParams) -> Self {
        let cache = CacheConfig::for_params(p);
        Self { kind: p.values.estimator, estimator: p.estimator, rd: p.values.sensor_size, frame: p.frame(), cache }
    }
}

/// Parameters that sense every pixel and do not filter (the exact estimator): the GPU's R at every pixel,
/// as sensed.
pub fn every_pixel(sensor: SensorKind, rd: u32, epsilon: f32) -> Setup {
    Setup {
        kind: EstimatorKind::Exact,
        estimator: EstimatorParams { sensor, indirect: Indirect::Epsilon(epsilon), background: Vec3::ZERO },
        rd,
        frame: FrameParams::every_pixel(Indirect::Epsilon(epsilon), Vec3::ZERO),
        cache: None,
    }
}

/// Renders `scene` on a validated GPU with the default strategy (unchecked: the strategy tests check it).
pub fn render(scene: &Scene, setup: &Setup, budget: Option<u64>) -> RenderOutput {
    gpu(|device| {
        let mut renderer = Renderer::builder(device, scene, setup.estimator.sensor, setup.rd)
            .estimator(setup.kind)
            .memory_budget(budget)
            .radiance_cache(setup.cache)
            .build_unchecked(StrategyKind::default())
            .unwrap();
        renderer.render(scene.image, &setup.frame, &Quiet).unwrap()
    })
}

/// `scene` rendered at the program's defaults with the paper's ε (0.1, an oracle without paths; 0 for
/// direct light alone) and `--aa on`, then `off`, each against the oracle integrated over each pixel's
/// square (`samples` each): whole image and interior.
pub fn against_the_area_oracle(scene: &Scene, epsilon: f32, samples: u32) -> [Comparison; 2] {
    against_the_area_oracle_with(scene, Overrides { epsilon: Some(epsilon), ..Default::default() }, samples)
}

/// [`against_the_area_oracle`] with the parameters `flags` set (e.g. a background), `--aa` aside; with
/// global illumination (no ε in `flags`), the render's radiance cache and the oracle's paths.
pub fn against_the_area_oracle_with(scene: &Scene, flags: Overrides, samples: u32) -> [Comparison; 2] {
    against_the_area_oracle_of(scene, scene, flags, samples)
}

/// [`against_the_area_oracle_with`], the oracle rendering `oracle_scene` (the same scene as the user gave it,
/// where the renderer's differs by an approximation being measured).
pub fn against_the_area_oracle_of(
    scene: &Scene,
    oracle_scene: &Scene,
    flags: Overrides,
    samples: u32,
) -> [Comparison; 2] {
    let params = |aa| {
        let flags = Overrides { aa: Some(aa), ..flags.clone() };
        RenderParams::resolve(None, &flags).unwrap()
    };
    let p = params(Antialiasing::On);
    let oracle =
        Integrator::new(oracle_scene, p.estimator, samples, 7).unwrap().render(scene.image, Antialiasing::On, &|_| ());
    let picture = |name: &str, rgb: &[Vec4], noise: Option<&[Vec4]>| Picture {
        name: name.into(),
        width: scene.image.width as usize,
        height: scene.image.height as usize,
        rgb: rgb.iter().map(|p| [p.x, p.y, p.z]).collect(),
        surface_id: Some(oracle.gbuffer.surface.iter().map(|&i| i as f32).collect()),
        std_error: noise.map(|n| n.iter().map(|p| [p.x, p.y, p.z]).collect()),
        emitter: Some(oracle.gbuffer.emission.iter().map(|e| e.truncate() != Vec3::ZERO).collect()),
    };
    [Antialiasing::On, Antialiasing::Off].map(|aa| {
        let p = params(aa);
        let out = render(scene, &Setup::of(&p), None);
        let reference = picture("oracle", &oracle.image, Some(&oracle.image_std_error));
        let c = compare(&picture("render", &out.image, None), &reference).unwrap();
        eprintln!(
            "aa {aa}: whole image {:.4} (own {:.4}, oracle noise {:.4}), interior {:.4} (own {:.4}); {} pixels supersampled",
            c.whole.relative_rmse,
            c.whole.own_error.unwrap(),
            c.whole.reference_noise.unwrap(),
            c.interior.relative_rmse,
            c.interior.own_error.unwrap(),
            out.supersampled.len()
        );
        c
    })
}

/// Ground (4 × 4 at y = 0), a back wall, a side wall (1.5 high) and a pillar (a box 0.3 × 1.2 × 0.3 at the
/// centre), all of albedo `albedo`, as `yard.obj` and `yard.mtl` in `dir`: an open scene lit from above.
pub fn courtyard_mesh(dir: &Path, albedo: f32) {
    let mut obj = String::from("mtllib yard.mtl\nusemtl stone\n");
    let mut n = 0;
    let mut quad = |obj: &mut String, name: &str, c: [Vec3; 4]| {
        obj.push_str(&format!("g {name}\n"));
        for p in c {
            obj.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        obj.push_str(&format!("f {} {} {} {}\n", n + 1, n + 2, n + 3, n + 4));
        n += 4;
    };
    let v = Vec3::new;
    quad(&mut obj, "ground", [v(-2.0, 0.0, 2.0), v(2.0, 0.0, 2.0), v(2.0, 0.0, -2.0), v(-2.0, 0.0, -2.0)]);
    quad(&mut obj, "back", [v(-2.0, 0.0, -2.0), v(2.0, 0.0, -2.0), v(2.0, 1.5, -2.0), v(-2.0, 1.5, -2.0)]);
    quad(&mut obj, "side", [v(-2.0, 0.0, 2.0), v(-2.0, 0.0, -2.0), v(-2.0, 1.5, -2.0), v(-2.0, 1.5, 2.0)]);
    // The pillar: four sides and a top, counter-clockwise from outside.
    let (a, b, h) = (-0.15f32, 0.15f32, 1.2f32);
    quad(&mut obj, "pillar", [v(a, 0.0, b), v(b, 0.0, b), v(b, h, b), v(a, h, b)]);
    quad(&mut obj, "pillar", [v(b, 0.0, b), v(b, 0.0, a), v(b, h, a), v(b, h, b)]);
    quad(&mut obj, "pillar", [v(b, 0.0, a), v(a, 0.0, a), v(a, h, a), v(b, h, a)]);
    quad(&mut obj, "pillar", [v(a, 0.0, a), v(a, 0.0, b), v(a, h, b), v(a, h, a)]);
    quad(&mut obj, "pillar", [v(a, h, b), v(b, h, b), v(b, h, a), v(a, h, a)]);
    std::fs::write(dir.join("yard.obj"), obj).unwrap();
    std::fs::write(dir.join("yard.mtl"), format!("newmtl stone\nKd {albedo} {albedo} {albedo}\n")).unwrap();
}
