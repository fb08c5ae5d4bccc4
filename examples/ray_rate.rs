//! The host's ray rate on a scene's BVH (`scene::bvh`), which the radiance cache's shadow rays, the
//! supersampling, the light hints and the reference all trace: shadow rays from points on the surfaces to
//! points on the lights, and nearest-hit rays from the same points into their hemispheres, on every core.
//! Prints the rates and a checksum of the answers, so that two builds of the walk can be compared for speed
//! and shown to agree: `cargo run --release --example ray_rate -- scene.toml [rays, default 400000]`.
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use sensorlight::light::groups::Lights;
use sensorlight::scene::Scene;
use sensorlight::scene::bvh::Bvh;
use sensorlight::scene::ray::Ray;

/// A point of the unit square from an index, by the golden ratio and the radical inverse (deterministic).
fn square(i: u32) -> (f32, f32) {
    ((i as f32 * 0.618_034).fract(), i.reverse_bits() as f32 / 2f32.powi(32))
}

/// A point on triangle `v` from a point of the unit square.
fn on_triangle(v: &[Vec3; 3], (u, w): (f32, f32)) -> Vec3 {
    let s = u.sqrt();
    v[0] * (1.0 - s) + v[1] * (s * (1.0 - w)) + v[2] * (s * w)
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or_else(|| anyhow::anyhow!("usage: ray_rate SCENE.toml [RAYS]"))?;
    let rays: u32 = args.next().map(|n| n.parse()).transpose()?.unwrap_or(400_000);
    let scene = Scene::load(std::path::Path::new(&path))?;
    let mesh = &scene.mesh;
    let start = Instant::now();
    let bvh = Bvh::of_mesh(mesh);
    println!("{} triangles: BVH built in {:.2} s", mesh.triangles.len(), start.elapsed().as_secs_f64());
    let lights = Lights::new(mesh);
    anyhow::ensure!(!lights.emitters.is_empty(), "the scene has no emitters to cast shadow rays at");
    let eps = mesh.scale() * 1e-4;
    // Points on the surfaces (a triangle by index, spread over the mesh), lifted off them.
    let n = mesh.triangles.len() as u64;
    let at = |i: u32| {
        let t = &mesh.triangles[((i as u64 * 2_654_435_761) % n) as usize];
        (on_triangle(&t.v, square(i)) + t.normal * eps, t.normal)
    };
    let start = Instant::now();
    let blocked: u32 = (0..rays)
        .into_par_iter()
        .map(|i| {
            let (p, _) = at(i);
            let e = &lights.emitters[i as usize % lights.emitters.len()];
            let q = on_triangle(&e.v, square(i.wrapping_mul(7) + 3));
            bvh.occluded(&Ray::new(p, q - p), 0.0, 1.0 - 1e-4) as u32
        })
        .sum();
    let shadow = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let (hits, checksum) = (0..rays)
        .into_par_iter()
        .map(|i| {
            let (p, normal) = at(i);
            let (u, w) = square(i.wrapping_mul(13) + 5);
            let (phi, z) = (u * std::f32::consts::TAU, w);
            let r = (1.0 - z * z).max(0.0).sqrt();
            let local = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            let (t, b) = normal.any_orthonormal_pair();
            let d = t * local.x + b * local.y + normal * local.z;
            bvh.intersect(&Ray::new(p, d), 0.0, f32::INFINITY).map_or((0u32, 0u64), |h| (1, h.triangle as u64))
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1.wrapping_add(b.1)));
    let nearest = start.elapsed().as_secs_f64();
    println!(
        "shadow rays: {:.2} M/s ({blocked} of {rays} blocked); nearest hits: {:.2} M/s ({hits} hit, checksum {checksum})",
        rays as f64 / shadow / 1e6,
        rays as f64 / nearest / 1e6
    );
    Ok(())
}
