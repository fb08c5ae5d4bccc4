//! A small glTF 2.0 test asset, written as `.glb` or as `.gltf` + `.bin`, and the same scene as an OBJ whose
//! triangles are transformed here (independently of the loader): a floor and a wall (one quad mesh, with
//! normals, instanced by two nodes), a red box under a parent node (translated, rotated, scaled), a mirrored
//! copy of it (negative scale), a light (the quad turned to face down, `KHR_materials_emissive_strength`)
//! and a camera.

use std::path::Path;

use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};

/// The light's emitted radiance: emissive factor 1 × strength.
pub const LIGHT_KE: f32 = 15.0;

/// The camera's node: where it is, and its rotation (about x, looking a little down).
pub const CAMERA_EYE: Vec3 = Vec3::new(0.0, 1.3, 3.4);
pub const CAMERA_PITCH: f32 = -0.25;

struct Node {
    mesh: usize,
    world: Mat4,
    json: Value,
}

const QUAD: [[f32; 3]; 4] = [[-0.5, 0.0, -0.5], [-0.5, 0.0, 0.5], [0.5, 0.0, 0.5], [0.5, 0.0, -0.5]];
const QUAD_INDICES: [u16; 6] = [0, 1, 2, 0, 2, 3];

fn cube() -> (Vec<[f32; 3]>, Vec<u16>) {
    let corner = |i: u16| [(i & 1) as f32 - 0.5, ((i >> 1) & 1) as f32 - 0.5, ((i >> 2) & 1) as f32 - 0.5];
    let positions = (0..8).map(corner).collect();
    // Each face counter-clockwise seen from outside.
    let faces: [[u16; 4]; 6] = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let indices = faces.iter().flat_map(|f| [f[0], f[1], f[2], f[0], f[2], f[3]]).collect();
    (positions, indices)
}

/// The nodes: mesh 0 is the quad (with normals), mesh 1 the cube; each with its world transform.
fn nodes() -> Vec<Node> {
    let trs = |t: Vec3, r: Quat, s: Vec3| Mat4::from_scale_rotation_translation(s, r, t);
    let node = |mesh: usize, material: usize, t: Vec3, r: Quat, s: Vec3, parent: Mat4| Node {
        mesh: mesh * 10 + material,
        world: parent * trs(t, r, s),
        json: json!({ "translation": t.to_array(), "rotation": r.to_array(), "scale": s.to_array() }),
    };
    let parent = trs(Vec3::new(0.0, 0.0, -0.2), Quat::IDENTITY, Vec3::ONE);
    vec![
        node(0, 0, Vec3::ZERO, Quat::IDENTITY, Vec3::new(4.0, 1.0, 4.0), Mat4::IDENTITY),
        node(
            0,
            0,
            Vec3::new(0.0, 1.0, -2.0),
            Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            Vec3::splat(4.0),
            Mat4::IDENTITY,
        ),
        node(1, 1, Vec3::new(0.3, 0.25, 0.0), Quat::from_rotation_y(0.5), Vec3::splat(0.5), parent),
        node(1, 1, Vec3::new(-0.8, 0.15, 0.5), Quat::IDENTITY, Vec3::new(-0.3, 0.3, 0.3), Mat4::IDENTITY),
        node(
            0,
            2,
            Vec3::new(0.0, 1.8, 0.0),
            Quat::from_rotation_x(std::f32::consts::PI),
            Vec3::splat(0.5),
            Mat4::IDENTITY,
        ),
    ]
}

/// The document, and its binary buffer (quad positions, normals, indices; cube positions, indices).
fn document(uri: Option<&str>, required: &[&str]) -> (Value, Vec<u8>) {
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut push = |bytes: &[u8], target: u32| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push(json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len(), "target": target }));
        bin.extend_from_slice(bytes);
        views.len() - 1
    };
    let floats = |v: &[[f32; 3]]| v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let shorts = |v: &[u16]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let (cube_positions, cube_indices) = cube();
    let quad_views =
        [push(&floats(&QUAD), 34962), push(&floats(&[[0.0, 1.0, 0.0]; 4]), 34962), push(&shorts(&QUAD_INDICES), 34963)];
    let cube_views = [push(&floats(&cube_positions), 34962), push(&shorts(&cube_indices), 34963)];
    let vec3 = |view: usize, count: usize, bounds: bool| {
        let mut a = json!({ "bufferView": view, "componentType": 5126, "count": count, "type": "VEC3" });
        if bounds {
            a["min"] = json!([-0.5, -0.5, -0.5]);
            a["max"] = json!([0.5, 0.5, 0.5]);
        }
        a
    };
    let scalar = |view: usize, count: usize| json!({ "bufferView": view, "componentType": 5123, "count": count, "type": "SCALAR" });
    let accessors = json!([
        vec3(quad_views[0], 4, true),
        vec3(quad_views[1], 4, false),
        scalar(quad_views[2], 6),
        vec3(cube_views[0], 8, true),
        scalar(cube_views[1], 36),
    ]);
    // A mesh per (shape, material) used: 0 quad grey, 2 quad light, 11 cube red.
    let mesh_ids = [0usize, 2, 11];
    let meshes: Vec<Value> = mesh_ids
        .iter()
        .map(|&m| {
            let (shape, material) = (m / 10, m % 10);
            let primitive = if shape == 0 {
                json!({ "attributes": { "POSITION": 0, "NORMAL": 1 }, "indices": 2, "material": material })
            } else {
                json!({ "attributes": { "POSITION": 3 }, "indices": 4, "material": material })
            };
            json!({ "name": format!("m{m}"), "primitives": [primitive] })
        })
        .collect();
    let nodes = nodes();
    let mut json_nodes: Vec<Value> = Vec::new();
    let mut roots = Vec::new();
    for (k, n) in nodes.iter().enumerate() {
        let mut j = n.json.clone();
        j["mesh"] = json!(mesh_ids.iter().position(|&m| m == n.mesh).unwrap());
        if k == 2 {
            // Under a parent that moves it.
            json_nodes.push(json!({ "translation": [0.0, 0.0, -0.2], "children": [json_nodes.len() + 1] }));
            roots.push(json_nodes.len() - 1);
            json_nodes.push(j);
        } else {
            roots.push(json_nodes.len());
            json_nodes.push(j);
        }
    }
    let camera_rotation = Quat::from_rotation_x(CAMERA_PITCH);
    json_nodes
        .push(json!({ "camera": 0, "translation": CAMERA_EYE.to_array(), "rotation": camera_rotation.to_array() }));
    roots.push(json_nodes.len() - 1);
    let mut buffer = json!({ "byteLength": bin.len() });
    if let Some(uri) = uri {
        buffer["uri"] = json!(uri);
    }
    let doc = json!({
        "asset": { "version": "2.0", "generator": "sensorlight tests" },
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "extensionsRequired": required,
        "scene": 0,
        "scenes": [{ "nodes": roots }],
        "nodes": json_nodes,
        "meshes": meshes,
        "cameras": [{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.01 } }],
        "materials": [
            { "name": "grey", "pbrMetallicRoughness": { "baseColorFactor": [0.7, 0.7, 0.7, 1.0], "metallicFactor": 0.0 } },
            { "name": "red", "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.2, 0.2, 1.0], "metallicFactor": 0.0 } },
            {
                "name": "light",
                "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0 },
                "emissiveFactor": [1.0, 1.0, 1.0],
                "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": LIGHT_KE } }
            }
        ],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [buffer],
    });
    (doc, bin)
}

/// Writes the asset as `name.glb` in `dir` (requiring `required` extensions) and returns its path.
pub fn write_glb(dir: &Path, name: &str, required: &[&str]) -> std::path::PathBuf {
    let (doc, mut bin) = document(None, required);
    let mut json = serde_json::to_vec(&doc).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::with_capacity(total);
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    let path = dir.join(format!("{name}.glb"));
    std::fs::write(&path, glb).unwrap();
    path
}

/// Writes the asset as `name.gltf` (pretty JSON, one value per line) and `name.bin` in `dir`.
pub fn write_gltf(dir: &Path, name: &str) -> std::path::PathBuf {
    write_gltf_edited(dir, name, |_| {})
}

/// [`write_gltf`], the document changed by `edit` first.
pub fn write_gltf_edited(dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> std::path::PathBuf {
    let (mut doc, bin) = document(Some(&format!("{name}.bin")), &[]);
    edit(&mut doc);
    std::fs::write(dir.join(format!("{name}.bin")), bin).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    path
}

/// The same scene as an OBJ + MTL in `dir`, its triangles transformed here; returns the OBJ's path.
pub fn write_obj(dir: &Path, name: &str) -> std::path::PathBuf {
    let (cube_positions, cube_indices) = cube();
    let mut obj = format!("mtllib {name}.mtl\n");
    let (mut vertices, mut normals) = (0, 0);
    for (k, n) in nodes().iter().enumerate() {
        let (shape, material) = (n.mesh / 10, n.mesh % 10);
        let (positions, indices): (Vec<[f32; 3]>, Vec<u16>) = if shape == 0 {
            (QUAD.to_vec(), QUAD_INDICES.to_vec())
        } else {
            (cube_positions.clone(), cube_indices.clone())
        };
        let mirrored = n.world.determinant() < 0.0;
        obj += &format!("g node{k}\nusemtl {}\n", ["grey", "red", "light"][material]);
        let normal = (glam::Mat3::from_mat4(n.world).inverse().transpose() * Vec3::Y).normalize();
        for t in indices.chunks_exact(3) {
            let t = if mirrored { [t[0], t[2], t[1]] } else { [t[0], t[1], t[2]] };
            let mut corners = Vec::new();
            for i in t {
                let p = n.world.transform_point3(Vec3::from(positions[i as usize]));
                obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
                vertices += 1;
                if shape == 0 {
                    obj += &format!("vn {} {} {}\n", normal.x, normal.y, normal.z);
                    normals += 1;
                    corners.push(format!("{vertices}//{normals}"));
                } else {
                    corners.push(vertices.to_string());
                }
            }
            obj += &format!("f {}\n", corners.join(" "));
        }
    }
    let path = dir.join(format!("{name}.obj"));
    std::fs::write(&path, obj).unwrap();
    std::fs::write(
        dir.join(format!("{name}.mtl")),
        format!(
            "newmtl grey\nKd 0.7 0.7 0.7\nnewmtl red\nKd 0.8 0.2 0.2\nnewmtl light\nKd 0 0 0\nKe {LIGHT_KE} {LIGHT_KE} {LIGHT_KE}\n"
        ),
    )
    .unwrap();
    path
}

/// A `.gltf` (written as `name.gltf` + `name.bin` in `dir`) of one quad: `corners` counter-clockwise,
/// `uvs` its TEXCOORD_0 (left out when `texcoord` is false), drawn with `material` (its JSON) whose texture 0
/// is the image `image` beside it. Returns its path.
pub fn textured_quad(
    dir: &Path,
    name: &str,
    (corners, uvs, texcoord): ([[f32; 3]; 4], [[f32; 2]; 4], bool),
    material: Value,
    image: &str,
) -> std::path::PathBuf {
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = bytemuck::cast_slice(&corners).to_vec();
    bin.extend_from_slice(bytemuck::cast_slice(&uvs));
    bin.extend_from_slice(bytemuck::cast_slice(&indices));
    bin.extend_from_slice(&[0, 0]);
    std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
    let (lo, hi) = corners
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &c| (lo.min(Vec3::from(c)), hi.max(Vec3::from(c))));
    let mut attributes = json!({ "POSITION": 0 });
    if texcoord {
        attributes["TEXCOORD_0"] = json!(1);
    }
    let doc = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": attributes, "indices": 2, "material": 0 }] }],
        "materials": [material],
        "textures": [{ "source": 0 }],
        "images": [{ "uri": image }],
        "buffers": [{ "uri": format!("{name}.bin"), "byteLength": bin.len() }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 32 },
            { "buffer": 0, "byteOffset": 80, "byteLength": 12 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": lo.to_array(), "max": hi.to_array() },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    });
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
    path
}
