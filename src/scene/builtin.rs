//! Scenes built in code: the probe the strategy self-check and benchmarks run on, and test scenes.

use glam::Vec3;

use super::material::{Group, Material};
use super::{Camera, ImageSize, Mesh, Scene};

/// Two triangles covering the rectangle `center ± half_u ± half_v`, wound so that the front faces `facing`.
pub fn rect(center: Vec3, half_u: Vec3, half_v: Vec3, facing: Vec3) -> Vec<[Vec3; 3]> {
    let c = [center - half_u - half_v, center + half_u - half_v, center + half_u + half_v, center - half_u + half_v];
    let tris = vec![[c[0], c[1], c[2]], [c[0], c[2], c[3]]];
    if half_u.cross(half_v).dot(facing) < 0.0 { tris.into_iter().map(|[a, b, c]| [a, c, b]).collect() } else { tris }
}

/// A scene from `(group name, material index, triangles)` groups.
pub fn from_groups(
    groups: Vec<(&str, usize, Vec<[Vec3; 3]>)>,
    materials: Vec<Material>,
    camera: Camera,
    size: ImageSize,
) -> Scene {
    let groups: Vec<Group> = groups
        .into_iter()
        .map(|(name, material, triangles)| Group {
            name: name.into(),
            material,
            triangles,
            normals: Vec::new(),
            uvs: Vec::new(),
            lightmap_uvs: Vec::new(),
        })
        .collect();
    let mut warnings = Vec::new();
    let mesh = Mesh::new(&groups, materials, Vec::new(), &mut warnings).expect("built-in scenes have triangles");
    let render = toml::Table::new();
    Scene {
        path: "(built in)".into(),
        mesh,
        camera,
        image: size,
        render,
        sun: None,
        sky: None,
        warnings,
        notes: Vec::new(),
        inputs: Vec::new(),
        mesh_file: None,
        camera_path: None,
    }
}

/// A room open towards the camera, 2 × 2 × 2 units, with a red and a green wall, a large ceiling light
/// (Ke 4) and a block: every kind of thing a sensor sees (emitter fronts and backs, walls in colour,
/// occluders near and far), with a light large enough that references converge fast.
pub fn lightbox(size: ImageSize) -> Scene {
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
    let camera = Camera::look_at(Vec3::new(0.0, 1.0, 3.4), c, y, 40.0).expect("valid camera");
    let material = |name: &str, kd: Vec3, ke: f32| Material::new(name, kd, Vec3::splat(ke));
    let materials = vec![
        material("white", Vec3::splat(0.7), 0.0),
        material("red", Vec3::new(0.7, 0.1, 0.1), 0.0),
        material("green", Vec3::new(0.1, 0.7, 0.1), 0.0),
        material("light", Vec3::splat(0.5), 4.0),
    ];
    from_groups(groups, materials, camera, size)
}
