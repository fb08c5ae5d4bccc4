//! Shading normals (OBJ `vn`): interpolated across each triangle in the G-buffer, its ray-cast twin and the
//! oracle, so that a tessellated sphere is shaded as a sphere, not facet by facet.

mod common;

use std::fmt::Write as _;
use std::path::Path;

use glam::Vec3;
use sensorlight::gbuffer::GBufferData;
use sensorlight::gbuffer::cast;
use sensorlight::scene::bvh::Bvh;
use sensorlight::scene::{ImageSize, Scene};

const CENTRE: Vec3 = Vec3::new(-0.1, 0.6, -0.3);
const RADIUS: f32 = 0.4;

/// A floor, a back wall, a sphere of 12 × 24 facets (15° apart) and a square light above, as an OBJ file
/// with its MTL and a scene file in `dir`; the sphere's corners carry their exact normals (`vn`) where
/// `smooth`, else none (flat facets).
fn sphere_scene(dir: &Path, smooth: bool, size: (u32, u32)) -> Scene {
    let mut obj = String::from("mtllib scene.mtl\n");
    let quad = |obj: &mut String, first: usize| {
        writeln!(obj, "f {} {} {} {}", first, first + 1, first + 2, first + 3).unwrap();
    };
    let mut vertices = 0;
    let mut rect = |obj: &mut String, name: &str, material: &str, corners: [Vec3; 4]| {
        writeln!(obj, "g {name}\nusemtl {material}").unwrap();
        for c in corners {
            writeln!(obj, "v {} {} {}", c.x, c.y, c.z).unwrap();
        }
        quad(obj, vertices + 1);
        vertices += 4;
    };
    let (x, z) = (1.2, 1.0);
    rect(
        &mut obj,
        "floor",
        "grey",
        [Vec3::new(-x, 0.0, -z), Vec3::new(-x, 0.0, z), Vec3::new(x, 0.0, z), Vec3::new(x, 0.0, -z)],
    );
    rect(
        &mut obj,
        "wall",
        "grey",
        [Vec3::new(-x, 0.0, -z), Vec3::new(x, 0.0, -z), Vec3::new(x, 1.5, -z), Vec3::new(-x, 1.5, -z)],
    );
    rect(
        &mut obj,
        "light",
        "light",
        [Vec3::new(0.2, 1.6, 0.0), Vec3::new(0.5, 1.6, 0.0), Vec3::new(0.5, 1.6, 0.3), Vec3::new(0.2, 1.6, 0.3)],
    );
    // The sphere (`meshes::sphere`, 12 stacks × 24 slices), each corner with the sphere's normal there.
    writeln!(obj, "g sphere\nusemtl blue").unwrap();
    for (k, t) in common::meshes::sphere(CENTRE, RADIUS, 12).iter().enumerate() {
        for p in t {
            let n = (*p - CENTRE).normalize();
            writeln!(obj, "v {} {} {}\nvn {} {} {}", p.x, p.y, p.z, n.x, n.y, n.z).unwrap();
        }
        let corner = |c: usize| {
            let v = vertices + 3 * k + c + 1;
            if smooth { format!("{v}//{}", 3 * k + c + 1) } else { v.to_string() }
        };
        writeln!(obj, "f {} {} {}", corner(0), corner(1), corner(2)).unwrap();
    }
    std::fs::write(dir.join("scene.obj"), obj).unwrap();
    std::fs::write(
        dir.join("scene.mtl"),
        "newmtl grey\nKd 0.6 0.6 0.6\nnewmtl blue\nKd 0.3 0.4 0.7\nnewmtl light\nKd 0 0 0\nKe 20 20 20\n",
    )
    .unwrap();
    let toml = format!(
        "mesh = \"scene.obj\"\n[camera]\neye = [0.4, 1.1, 2.0]\ntarget = [-0.1, 0.5, -0.3]\nup = [0, 1, 0]\n\
         vfov_deg = 40\n[image]\nwidth = {}\nheight = {}\n",
        size.0, size.1
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    Scene::load(&dir.join("scene.toml")).unwrap()
}

/// The sphere's pixels away from its outline: their normal (turned to the camera), and the sphere's own
/// normal at their point.
fn sphere_normals(scene: &Scene, g: &GBufferData) -> Vec<(Vec3, Vec3)> {
    let id = scene.mesh.surfaces.iter().position(|s| s.name.starts_with("sphere/")).unwrap() as u32 + 1;
    let w = g.size.width as usize;
    (0..g.surface.len())
        .filter(|&i| {
            let (x, y) = (i % w, i / w);
            x > 0
                && y > 0
                && x + 1 < w
                && y + 1 < g.size.height as usize
                && [i - 1, i + 1, i - w, i + w, i].iter().all(|&j| g.surface[j] == id)
        })
        .map(|i| (g.normal[i].truncate(), (g.position[i].truncate() - CENTRE).normalize()))
        .collect()
}

fn worst_degrees(pairs: &[(Vec3, Vec3)]) -> f32 {
    pairs.iter().map(|(a, b)| a.dot(*b).clamp(-1.0, 1.0).acos().to_degrees()).fold(0.0, f32::max)
}

/// With `vn`, the G-buffer's normal (rasterised, and its ray-cast twin) on the sphere is the sphere's own
/// normal at the point seen (interpolating the corners' unit normals by the point's barycentric
/// coordinates gives exactly the direction from the centre: a facet's point is the same combination of its
/// corners); without, it is the facet's, off by up to half the 15° between facets.
#[test]
fn the_gbuffer_shades_a_tessellated_sphere_with_its_interpolated_normals() {
    let size = ImageSize { width: 96, height: 72 };
    for smooth in [true, false] {
        let dir = common::scratch(&format!("shading-gbuffer-{smooth}"));
        let scene = sphere_scene(&dir, smooth, (size.width, size.height));
        let cpu = cast::cast(&scene, &Bvh::build(&scene.mesh.triangles), size);
        let gpu = common::gpu(|device| common::raster_gbuffer(device, &scene, size).2);
        let (cpu_pairs, gpu_pairs) = (sphere_normals(&scene, &cpu), sphere_normals(&scene, &gpu));
        assert!(cpu_pairs.len() > 500, "the sphere covers {} pixels: the test would prove little", cpu_pairs.len());
        let (cpu_worst, gpu_worst) = (worst_degrees(&cpu_pairs), worst_degrees(&gpu_pairs));
        if smooth {
            assert!(cpu_worst < 0.1, "ray cast: {cpu_worst}° from the sphere's normal");
            assert!(gpu_worst < 0.5, "rasterised: {gpu_worst}° from the sphere's normal");
        } else {
            assert!(cpu_worst > 4.0 && gpu_worst > 4.0, "flat facets: {cpu_worst}°, {gpu_worst}°");
        }
    }
}

/// A smooth sphere by a wall at the defaults (direct light, so the oracle converges) against the oracle over
/// pixel squares, which shades with the same normals: within 2 % inside and 3 % over the whole image (the
/// sensors' frames, the lights' closed form and the refinement all take the interpolated normal).
#[test]
fn a_smooth_sphere_at_the_defaults_within_two_percent_of_the_oracle() {
    let dir = common::scratch("shading-oracle");
    let scene = sphere_scene(&dir, true, (128, 96));
    let [on, _] = common::against_the_area_oracle(&scene, 0.0, 2048);
    assert!(on.interior.own_error.unwrap() <= 0.02, "interior {:?}", on.interior);
    assert!(on.whole.own_error.unwrap() <= 0.03, "whole image {:?}", on.whole);
}
