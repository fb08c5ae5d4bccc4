//! Meshes built in code for the cluster tests: a closed sphere, a floor, a lamp.

use glam::Vec3;
use sensorlight::scene::Mesh;
use sensorlight::scene::material::{Group, Material};

/// A closed UV sphere of `2 · slices · (stacks − 1)` triangles, counter-clockwise from outside; each grid
/// point computed once, so shared corners are equal bit for bit.
pub fn sphere(center: Vec3, radius: f32, stacks: usize) -> Vec<[Vec3; 3]> {
    let slices = 2 * stacks;
    let ring = |i: usize, j: usize| {
        let (theta, phi) =
            (std::f32::consts::PI * i as f32 / stacks as f32, std::f32::consts::TAU * j as f32 / slices as f32);
        center + radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    let grid: Vec<Vec<Vec3>> = (1..stacks).map(|i| (0..slices).map(|j| ring(i, j)).collect()).collect();
    let (north, south) = (center + radius * Vec3::Y, center - radius * Vec3::Y);
    let at = |i: usize, j: usize| grid[i - 1][j % slices];
    let mut t = Vec::new();
    for j in 0..slices {
        t.push([north, at(1, j + 1), at(1, j)]);
        t.push([south, at(stacks - 1, j), at(stacks - 1, j + 1)]);
    }
    for i in 1..stacks - 1 {
        for j in 0..slices {
            t.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            t.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    t
}

/// A grid of `n × n` quads in the plane y = `y`, facing up.
pub fn plane(y: f32, n: usize) -> Vec<[Vec3; 3]> {
    let p = |i: usize, j: usize| Vec3::new(i as f32 / n as f32 * 4.0 - 2.0, y, j as f32 / n as f32 * 4.0 - 2.0);
    (0..n)
        .flat_map(|i| {
            (0..n).flat_map(move |j| [[p(i, j), p(i, j + 1), p(i + 1, j + 1)], [p(i, j), p(i + 1, j + 1), p(i + 1, j)]])
        })
        .collect()
}

/// A sphere (surface 1), a finely tessellated floor (surface 2) and a finely tessellated emitter (surface 3).
pub fn scene() -> Mesh {
    let mut lamp = plane(3.0, 24);
    lamp.iter_mut().for_each(|t| t.swap(1, 2)); // facing down
    mesh(&[("ball", 0, sphere(Vec3::ZERO, 1.0, 64)), ("floor", 0, plane(-1.5, 48)), ("lamp", 1, lamp)])
}

/// A mesh of named groups of `triangles`, each grey (material 0) or a lamp (material 1).
pub fn mesh(groups: &[(&str, usize, Vec<[Vec3; 3]>)]) -> Mesh {
    let materials =
        vec![Material::new("grey", Vec3::splat(0.5), Vec3::ZERO), Material::new("lamp", Vec3::ZERO, Vec3::ONE)];
    let groups: Vec<Group> = groups
        .iter()
        .map(|(name, material, triangles)| Group {
            name: name.to_string(),
            material: *material,
            triangles: triangles.clone(),
            normals: Vec::new(),
            uvs: Vec::new(),
            lightmap_uvs: Vec::new(),
        })
        .collect();
    Mesh::new(&groups, materials, Vec::new(), &mut Vec::new()).unwrap()
}
