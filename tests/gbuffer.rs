//! The G-buffer raster pass against a CPU ray cast through the same pixel centres.

mod common;

use glam::Vec4;
use sensorlight::gbuffer::GBufferData;
use sensorlight::gbuffer::cast as cpu_gbuffer;
use sensorlight::gpu_scene::GpuScene;
use sensorlight::passes::gbuffer::{self, GBufferPass};
use sensorlight::scene::bvh::Bvh;
use sensorlight::scene::{ImageSize, NO_SURFACE, Scene};

fn gpu_gbuffer(scene: &Scene, size: ImageSize) -> GBufferData {
    common::gpu(|device| {
        let gpu_scene = GpuScene::upload(device, scene, None, None).unwrap();
        let pass = GBufferPass::new(device, &gpu_scene).unwrap();
        let near = gbuffer::NEAR * scene.mesh.scale();
        pass.render(device, &gpu_scene, &scene.camera, size, near).unwrap().read_back(device).unwrap()
    })
}

/// Pixels next to a change of surface in the CPU image: raster and ray cast may legitimately differ there.
fn silhouettes(g: &GBufferData) -> Vec<bool> {
    let (w, h) = (g.size.width as i64, g.size.height as i64);
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let id = g.surface[i as usize];
            [(-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, 1), (-1, 1), (1, -1)].iter().any(|(dx, dy)| {
                let (nx, ny) = (x + dx, y + dy);
                nx >= 0 && ny >= 0 && nx < w && ny < h && g.surface[(ny * w + nx) as usize] != id
            })
        })
        .collect()
}

fn check(scene_file: &str, size: ImageSize, min_surfaces: usize) {
    let scene = Scene::load(&common::project(scene_file)).unwrap();
    let cpu = cpu_gbuffer::cast(&scene, &Bvh::build(&scene.mesh.triangles), size);
    let gpu = gpu_gbuffer(&scene, size);
    let edge = silhouettes(&cpu);
    let tolerance = 1e-4 * scene.mesh.scale();
    let (mut compared, mut same_id, mut same_normal, mut same_rest) = (0, 0, 0, 0);
    for (i, _) in edge.iter().enumerate().filter(|(_, on_edge)| !**on_edge) {
        compared += 1;
        same_id += (cpu.surface[i] == gpu.surface[i]) as usize;
        let background = cpu.surface[i] == NO_SURFACE && gpu.surface[i] == NO_SURFACE;
        let (cn, gn) = (cpu.normal[i], gpu.normal[i]);
        same_normal += (background || (cn.truncate().dot(gn.truncate()) > 0.9999 && cn.w == gn.w)) as usize;
        let close = |a: Vec4, b: Vec4, tol: f32| (a - b).abs().max_element() <= tol;
        same_rest += (close(cpu.position[i], gpu.position[i], tolerance)
            && close(cpu.albedo[i], gpu.albedo[i], 1e-6)
            && close(cpu.emission[i], gpu.emission[i], 1e-6)) as usize;
    }
    let visible: std::collections::BTreeSet<u32> = cpu.surface.iter().copied().filter(|&s| s != NO_SURFACE).collect();
    assert!(visible.len() >= min_surfaces, "only {} surfaces visible: the test would prove little", visible.len());
    assert!(compared as f32 > 0.6 * cpu.surface.len() as f32, "silhouettes cover too much of the image");
    for (what, n) in
        [("surface id", same_id), ("normal and facing", same_normal), ("position, albedo, emission", same_rest)]
    {
        let ratio = n as f64 / compared as f64;
        assert!(
            ratio >= 0.99,
            "{scene_file}: {what} agrees on {:.2} % of {compared} pixels (need 99 %)",
            100.0 * ratio
        );
    }
    // The light is seen from below: some pixels carry its emission, and only front faces emit.
    assert!(
        gpu.emission.iter().any(|e| e.max_element() > 1.0),
        "{scene_file}: the light's emission is not in the G-buffer"
    );
}

#[test]
fn shipped_cornell_box_matches_ray_cast() {
    check("scenes/cornell/cornell.toml", ImageSize { width: 96, height: 80 }, 10);
}

#[test]
fn mcguire_cornell_box_matches_ray_cast() {
    check("scenes/cornell-mcguire/cornell-mcguire.toml", ImageSize { width: 80, height: 96 }, 10);
}
