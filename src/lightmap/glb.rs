//! The baked scene as a glTF 2.0 binary (`.glb`): every local triangle with its lightmap coordinates as
//! `TEXCOORD_1`, its materials, base colour textures and emission, and the scene's camera; the lightmap
//! itself is the linear float EXR beside it, which each material names in its `extras`:
//!
//! ```json
//! "extras": { "lightmap": { "uri": "room.lightmap.exr", "page": 0, "texCoord": 1,
//!                           "quantity": "irradiance/pi", "encoding": "linear" } }
//! ```
//!
//! With `--format rgbm` or `hdr`, `"alternate": { "uri": …, "encoding": "rgbm", "range": 8 }` (or
//! `"encoding": "rgbe"`) names the same light as an 8-bit PNG or a Radiance HDR beside it.
//!
//! A surface shows `baseColorFactor × baseColorTexture(TEXCOORD_0) × lightmap(TEXCOORD_1)` (bilinear), plus
//! its emission. glTF has no ratified lightmap extension: `EXT_lightmap`-style drafts and
//! `MSFT_lod`-era proposals were considered; an engine's importer maps `extras.lightmap` to its own slot
//! (three.js `material.lightMap` with `channel = 1`, Godot `LightmapGI` data, Bevy `Lightmap`), see the
//! README. Texture coordinates follow glTF: (0, 0) is the image's top-left corner, as the EXR's first row.

use anyhow::{Result, ensure};
use glam::{Mat3, Quat, Vec3};
use serde_json::{Value, json};

use super::unwrap::Unwrapped;
use crate::scene::{Camera, ImageSize, Mesh, Texture};

/// What the lightmap files are called beside the `.glb`.
pub struct LightmapFile<'a> {
    /// The linear float EXR: one file name per page (relative to the `.glb`).
    pub uris: &'a [String],
    /// The same light in another encoding, where asked (`--format`): its files per page and its
    /// `extras.lightmap.alternate` (`"encoding"` and, for RGBM, `"range"`; the uri is added per page).
    pub alternate: Option<(&'a [String], Value)>,
}

/// The glTF binary of `mesh`'s local triangles laid in the lightmap by `unwrapped`, seen by `camera` at
/// `size`'s aspect ratio.
pub fn encode(
    mesh: &Mesh,
    unwrapped: &Unwrapped,
    lightmap: &LightmapFile<'_>,
    (camera, size): (&Camera, ImageSize),
) -> Result<Vec<u8>> {
    let mut bin = Bin::default();
    let mut accessors = Vec::new();
    let mut primitives = Vec::new();
    let mut materials = Vec::new();
    let mut textures = Textures::default();
    let local = unwrapped.uv.len();
    // One primitive per (material, page): a primitive reads one page.
    let mut keys: Vec<(usize, u32)> = (0..local)
        .map(|t| (mesh.surfaces[mesh.triangles[t].surface as usize - 1].material, unwrapped.page[t]))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    for &(m, page) in &keys {
        let triangles: Vec<usize> = (0..local)
            .filter(|&t| {
                mesh.surfaces[mesh.triangles[t].surface as usize - 1].material == m && unwrapped.page[t] == page
            })
            .collect();
        let material = &mesh.materials[m];
        let textured = material.kd_map.is_some() && !mesh.uvs.is_empty();
        let corners = |f: &dyn Fn(usize, usize) -> [f32; 3]| -> Vec<[f32; 3]> {
            triangles.iter().flat_map(|&t| (0..3).map(move |k| (t, k))).map(|(t, k)| f(t, k)).collect()
        };
        let positions = corners(&|t, k| mesh.triangles[t].v[k].to_array());
        let normals = corners(&|t, k| mesh.shading.get(t).map_or(mesh.triangles[t].normal, |n| n[k]).to_array());
        let uv1: Vec<[f32; 2]> = triangles.iter().flat_map(|&t| unwrapped.uv[t].map(|p| p.to_array())).collect();
        let mut attributes = serde_json::Map::new();
        attributes.insert("POSITION".into(), bin.vec3s(&mut accessors, &positions, true).into());
        attributes.insert("NORMAL".into(), bin.vec3s(&mut accessors, &normals, false).into());
        if textured {
            let uv0: Vec<[f32; 2]> = triangles.iter().flat_map(|&t| mesh.uvs[t].map(|p| p.to_array())).collect();
            attributes.insert("TEXCOORD_0".into(), bin.vec2s(&mut accessors, &uv0).into());
        }
        attributes.insert("TEXCOORD_1".into(), bin.vec2s(&mut accessors, &uv1).into());
        let index = materials.len();
        let name = if unwrapped.pages > 1 { format!("{}@{page}", material.name) } else { material.name.clone() };
        let mut pbr = json!({
            "baseColorFactor": [material.kd.x, material.kd.y, material.kd.z, 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        });
        if textured && let Some(k) = material.kd_map {
            pbr["baseColorTexture"] =
                json!({ "index": textures.index(k, &mesh.textures[k], &mut bin)?, "texCoord": 0 });
        }
        // The renderer shows a surface from either side, and a wall may face out of the room it closes.
        let mut gltf_material = json!({
            "name": name,
            "doubleSided": true,
            "pbrMetallicRoughness": pbr,
            "extras": { "lightmap": {
                "uri": lightmap.uris[page as usize], "page": page, "texCoord": 1,
                "quantity": "irradiance/pi", "encoding": "linear",
            }},
        });
        if let Some((uris, encoding)) = &lightmap.alternate {
            let mut alternate = encoding.clone();
            alternate["uri"] = json!(uris[page as usize]);
            gltf_material["extras"]["lightmap"]["alternate"] = alternate;
        }
        if let Some(cutout) = material.cutout.filter(|c| textured && Some(c.map) == material.kd_map) {
            gltf_material["alphaMode"] = json!("MASK");
            gltf_material["alphaCutoff"] = json!(cutout.threshold);
        }
        if material.is_emitter() {
            let strength = material.ke.max_element();
            let factor = material.ke / strength;
            gltf_material["emissiveFactor"] = json!([factor.x, factor.y, factor.z]);
            if strength != 1.0 {
                gltf_material["extensions"] =
                    json!({ "KHR_materials_emissive_strength": { "emissiveStrength": strength } });
            }
        }
        materials.push(gltf_material);
        primitives.push(json!({ "attributes": attributes, "material": index, "mode": 4 }));
    }
    let emissive = materials.iter().any(|m| m.get("extensions").is_some());
    let rotation = Quat::from_mat3(&Mat3::from_cols(camera.right, camera.up, -camera.forward)).normalize();
    let mut document = json!({
        "asset": { "version": "2.0", "generator": concat!("sensorlight ", env!("CARGO_PKG_VERSION"), " bake") },
        "scene": 0,
        "scenes": [{ "nodes": [0, 1] }],
        "nodes": [
            { "name": "baked", "mesh": 0 },
            { "name": "camera", "camera": 0, "translation": camera.eye.to_array(), "rotation": rotation.to_array() },
        ],
        "cameras": [{ "type": "perspective", "perspective": {
            "yfov": camera.vfov, "aspectRatio": size.width as f32 / size.height as f32,
            "znear": (mesh.scale() * 1e-4).max(1e-6),
        }}],
        "meshes": [{ "name": "baked", "primitives": primitives }],
        "materials": materials,
        "accessors": accessors,
    });
    if emissive {
        document["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
    }
    if !textures.textures.is_empty() {
        document["textures"] = Value::Array(textures.textures);
        document["images"] = Value::Array(textures.images);
        // Linear filtering with mipmaps, repeating: what the renderer samples (`scene::texture`).
        document["samplers"] = json!([{ "magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497 }]);
    }
    document["bufferViews"] = Value::Array(bin.views);
    document["buffers"] = json!([{ "byteLength": bin.data.len() }]);
    glb(&serde_json::to_vec(&document)?, &bin.data)
}

/// The binary buffer and its views.
#[derive(Default)]
struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
}

impl Bin {
    /// Appends `bytes` as a buffer view (4-byte aligned); returns its index.
    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        self.views.push(json!({ "buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len() }));
        self.data.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// A VEC3 float accessor (with its bounds where `bounds`: POSITION needs them); returns its index.
    fn vec3s(&mut self, accessors: &mut Vec<Value>, values: &[[f32; 3]], bounds: bool) -> usize {
        let view = self.view(bytemuck::cast_slice(values));
        let mut accessor = json!({ "bufferView": view, "componentType": 5126, "count": values.len(), "type": "VEC3" });
        if bounds {
            let (lo, hi) = values.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(Vec3::from(*v)), hi.max(Vec3::from(*v)))
            });
            accessor["min"] = json!(lo.to_array());
            accessor["max"] = json!(hi.to_array());
        }
        accessors.push(accessor);
        accessors.len() - 1
    }

    fn vec2s(&mut self, accessors: &mut Vec<Value>, values: &[[f32; 2]]) -> usize {
        let view = self.view(bytemuck::cast_slice(values));
        accessors.push(json!({ "bufferView": view, "componentType": 5126, "count": values.len(), "type": "VEC2" }));
        accessors.len() - 1
    }
}

/// The base colour textures written so far, each once.
#[derive(Default)]
struct Textures {
    /// The mesh's texture index of each glTF texture.
    written: Vec<usize>,
    textures: Vec<Value>,
    images: Vec<Value>,
}

impl Textures {
    /// The glTF texture of the mesh's texture `k`, written as a PNG into `bin` the first time.
    fn index(&mut self, k: usize, texture: &Texture, bin: &mut Bin) -> Result<usize> {
        if let Some(i) = self.written.iter().position(|&w| w == k) {
            return Ok(i);
        }
        let level = &texture.levels[0];
        let rgba: &[u8] = bytemuck::cast_slice(&level.texels);
        let mut png = Vec::new();
        crate::output::png::encode_rgba8(&mut png, level.width, level.height, rgba)?;
        let view = bin.view(&png);
        self.images.push(json!({ "bufferView": view, "mimeType": "image/png", "name": texture.name }));
        self.textures.push(json!({ "source": self.images.len() - 1, "sampler": 0 }));
        self.written.push(k);
        Ok(self.textures.len() - 1)
    }
}

/// The GLB container: a 12-byte header, the JSON chunk (padded with spaces) and the BIN chunk (padded
/// with zeros), each 4-byte aligned.
fn glb(json: &[u8], bin: &[u8]) -> Result<Vec<u8>> {
    let pad = |n: usize| (4 - n % 4) % 4;
    let (json_len, bin_len) = (json.len() + pad(json.len()), bin.len() + pad(bin.len()));
    let total = 12 + 8 + json_len + 8 + bin_len;
    ensure!(total <= u32::MAX as usize, "the baked scene needs {total} bytes, more than a .glb holds (4 GiB)");
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json_len as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    out.resize(out.len() + pad(json.len()), b' ');
    out.extend_from_slice(&(bin_len as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out.resize(out.len() + pad(bin.len()), 0);
    Ok(out)
}
