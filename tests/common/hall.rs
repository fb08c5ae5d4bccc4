//! A small closed hall built in code, the suite's real interior (`scripts/make_hall.py` writes the large
//! one): a room 12 × 6 × 8 m with two rows of fluted columns (two surfaces per flute), spheres on
//! pedestals between them, a red and a green end wall, lit by two ceiling panels; the camera inside.

use glam::Vec3;
use sensorlight::scene::builtin::rect;
use sensorlight::scene::{Camera, Scene};

use super::{material, scene};

/// Flutes around a column, facets per flute, and the column's radius and flute depth (metres).
const FLUTES: usize = 24;
const FLUTE_FACETS: usize = 6;
const RADIUS: f32 = 0.35;
const FLUTE_DEPTH: f32 = 0.05;
const HEIGHT: f32 = 6.0;

/// A closed box, faces outwards.
fn cuboid(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let (c, h) = ((lo + hi) / 2.0, (hi - lo) / 2.0);
    let mut t = Vec::new();
    for (axis, u, v) in [(Vec3::X, Vec3::Y, Vec3::Z), (Vec3::Y, Vec3::Z, Vec3::X), (Vec3::Z, Vec3::X, Vec3::Y)] {
        for s in [1.0f32, -1.0] {
            let n = axis * s;
            t.extend(rect(c + n * h.dot(axis), u * h.dot(u), v * h.dot(v), n));
        }
    }
    t
}

/// A fluted shaft of `rings` rows between y0 and y1 around (x, z), outwards.
fn shaft(x: f32, z: f32, (y0, y1): (f32, f32), rings: usize) -> Vec<[Vec3; 3]> {
    let around = FLUTES * FLUTE_FACETS;
    let profile: Vec<(f32, f32)> = (0..around)
        .map(|s| {
            let t = (s % FLUTE_FACETS) as f32 / FLUTE_FACETS as f32;
            let r = RADIUS - FLUTE_DEPTH * (std::f32::consts::PI * t).sin();
            let phi = std::f32::consts::TAU * s as f32 / around as f32;
            (r * phi.cos(), r * phi.sin())
        })
        .collect();
    let at = |j: usize, s: usize| {
        let (px, pz) = profile[s % around];
        Vec3::new(x + px, y0 + (y1 - y0) * j as f32 / rings as f32, z + pz)
    };
    let mut t = Vec::new();
    for j in 0..rings {
        for s in 0..around {
            let (a, b, c, d) = (at(j, s), at(j, s + 1), at(j + 1, s + 1), at(j + 1, s));
            t.push([a, d, c]);
            t.push([a, c, b]);
        }
    }
    t
}

/// The hall: `rings` rows per column shaft (each column `2 · 144 · rings` triangles), spheres of
/// `stacks` stacks, at `size`.
pub fn hall(rings: usize, stacks: usize, size: (u32, u32)) -> Scene {
    let (hx, hy, hz) = (6.0f32, HEIGHT, 4.0f32);
    let mut shell = Vec::new();
    shell.extend(rect(Vec3::new(0.0, 0.0, 0.0), Vec3::X * hx, Vec3::Z * hz, Vec3::Y));
    shell.extend(rect(Vec3::new(0.0, hy, 0.0), Vec3::X * hx, Vec3::Z * hz, -Vec3::Y));
    shell.extend(rect(Vec3::new(0.0, hy / 2.0, -hz), Vec3::X * hx, Vec3::Y * hy / 2.0, Vec3::Z));
    shell.extend(rect(Vec3::new(0.0, hy / 2.0, hz), Vec3::X * hx, Vec3::Y * hy / 2.0, -Vec3::Z));
    let west = rect(Vec3::new(-hx, hy / 2.0, 0.0), Vec3::Z * hz, Vec3::Y * hy / 2.0, Vec3::X);
    let east = rect(Vec3::new(hx, hy / 2.0, 0.0), Vec3::Z * hz, Vec3::Y * hy / 2.0, -Vec3::X);
    let mut panels = Vec::new();
    for x in [-2.5f32, 2.5] {
        panels.extend(rect(Vec3::new(x, hy - 0.02, 0.0), Vec3::X * 0.8, Vec3::Z * 0.5, -Vec3::Y));
    }
    let (mut columns, mut boxes) = (Vec::new(), Vec::new());
    for x in [-3.0f32, 0.0, 3.0] {
        for z in [-2.2f32, 2.2] {
            boxes.extend(cuboid(Vec3::new(x - 0.5, 0.0, z - 0.5), Vec3::new(x + 0.5, 0.3, z + 0.5)));
            boxes.extend(cuboid(Vec3::new(x - 0.5, hy - 0.7, z - 0.5), Vec3::new(x + 0.5, hy, z + 0.5)));
            columns.extend(shaft(x, z, (0.3, hy - 0.7), rings));
        }
    }
    let (mut spheres, mut pedestals) = (Vec::new(), Vec::new());
    for x in [-1.5f32, 1.5] {
        pedestals.extend(cuboid(Vec3::new(x - 0.3, 0.0, -0.3), Vec3::new(x + 0.3, 0.9, 0.3)));
        spheres.extend(super::meshes::sphere(Vec3::new(x, 1.35, 0.0), 0.45, stacks));
    }
    let groups = vec![
        ("shell", 0, shell),
        ("west", 1, west),
        ("east", 2, east),
        ("columns", 3, columns),
        ("boxes", 3, boxes),
        ("pedestals", 0, pedestals),
        ("spheres", 4, spheres),
        ("panels", 5, panels),
    ];
    let materials = vec![
        material("stone", 0.6, 0.0),
        sensorlight::scene::material::Material::new("red", Vec3::new(0.65, 0.12, 0.1), Vec3::ZERO),
        sensorlight::scene::material::Material::new("green", Vec3::new(0.15, 0.5, 0.2), Vec3::ZERO),
        material("marble", 0.8, 0.0),
        material("bronze", 0.5, 0.0),
        material("panel", 0.8, 12.0),
    ];
    let camera = Camera::look_at(Vec3::new(-5.5, 1.7, 0.9), Vec3::new(4.0, 2.2, -0.5), Vec3::Y, 60.0).unwrap();
    scene(groups, materials, camera, size)
}
