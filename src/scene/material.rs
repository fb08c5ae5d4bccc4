//! What a loader makes of a file, whatever its format (OBJ + MTL, glTF, the built-in scenes): materials
//! and their cut-outs, groups of triangles, and the errors that name a file and line.

use std::path::PathBuf;

use glam::{Vec2, Vec3};

use super::texture::Texture;

/// A user error in a scene file, with its location.
#[derive(Debug, thiserror::Error)]
#[error("{file}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct LoadError {
    pub file: PathBuf,
    pub line: Option<usize>,
    pub message: String,
}

/// A material as this renderer uses it: diffuse albedo and emitted radiance, linear RGB.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// The albedo, or with `kd_map` the factor its texture is multiplied by.
    pub kd: Vec3,
    /// The emitted radiance, or with `ke_map` the factor its texture is multiplied by.
    pub ke: Vec3,
    /// The index of its colour texture in the mesh's textures (`map_Kd`, glTF `baseColorTexture`).
    pub kd_map: Option<usize>,
    /// The index of its emission texture in the mesh's textures (`map_Ke`, glTF `emissiveTexture`).
    pub ke_map: Option<usize>,
    /// Where it is cut out (`map_d`, glTF `alphaMode` MASK): no light is sent or stopped there.
    pub cutout: Option<Cutout>,
    /// The format it was read from: messages about it use that format's words.
    pub format: MaterialFormat,
}

/// The file format a material was read from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MaterialFormat {
    #[default]
    Mtl,
    Gltf,
}

impl MaterialFormat {
    /// What the format calls the albedo: MTL's `Kd`, glTF's base colour.
    pub fn albedo_word(self) -> &'static str {
        match self {
            Self::Mtl => "Kd",
            Self::Gltf => "base colour",
        }
    }
}

/// An alpha test: a point of the surface exists where its texture's alpha there (bilinear, full resolution)
/// is at least `threshold` (glTF's cutoff divided by its base colour factor's alpha; MTL's `map_d` 0.5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cutout {
    /// The texture, in the mesh's textures, whose alpha is tested.
    pub map: usize,
    pub threshold: f32,
}

impl Cutout {
    /// MTL's `map_d`: cut out where the mask is under a half.
    pub const MTL_THRESHOLD: f32 = 0.5;
}

/// The largest `Kd`/`Ke` component accepted: its square must stay finite in `f32` (the reference's variance),
/// with room for sums over many samples.
pub const MAX_COLOUR: f32 = 1e18;

impl Material {
    pub const DEFAULT_KD: f32 = 0.8;

    /// A flat-coloured material: albedo `kd`, emitted radiance `ke`, no texture.
    pub fn new(name: &str, kd: Vec3, ke: Vec3) -> Self {
        Self { name: name.to_owned(), kd, ke, kd_map: None, ke_map: None, cutout: None, format: MaterialFormat::Mtl }
    }

    /// The same material without its textures: what a surface that gives no texture coordinates uses.
    pub fn untextured(&self) -> Self {
        Self { kd_map: None, ke_map: None, cutout: None, ..self.clone() }
    }

    pub fn is_emitter(&self) -> bool {
        self.ke.max_element() > 0.0
    }

    /// Whether a texture colours, lights or cuts it out: then its surfaces need texture coordinates.
    pub fn is_textured(&self) -> bool {
        self.kd_map.is_some() || self.ke_map.is_some() || self.cutout.is_some()
    }
}

/// One polygon soup group as the file defines it: an OBJ `g`/`o` name (a glTF mesh's) and one material.
#[derive(Clone, Debug)]
pub struct Group {
    pub name: String,
    pub material: usize,
    /// Triangles, fan-triangulated from the file's polygons, in file order.
    pub triangles: Vec<[Vec3; 3]>,
    /// Each triangle's corners' shading normals (`vn`, as the file gives them), or empty where some face of
    /// the group gives none: then it is shaded flat.
    pub normals: Vec<[Vec3; 3]>,
    /// Each triangle's corners' texture coordinates, (0, 0) the image's top-left corner (an OBJ `vt` (u, v)
    /// is (u, 1 − v)); empty where some face of the group gives none.
    pub uvs: Vec<[Vec2; 3]>,
    /// Each triangle's corners' lightmap coordinates (glTF's `TEXCOORD_1`), as `uvs` places them; empty
    /// where the group has none (`sensorlight bake` then unwraps the mesh itself).
    pub lightmap_uvs: Vec<[Vec2; 3]>,
}

/// A file's mesh as a loader read it: its groups, materials, textures, what it warned of, the files read.
#[derive(Default)]
pub struct Imported {
    pub groups: Vec<Group>,
    pub materials: Vec<Material>,
    /// The colour textures the materials name (`Material::kd_map`), each file once.
    pub textures: Vec<Texture>,
    pub warnings: Vec<String>,
    /// The files read: the OBJ, then each material library, then the textures.
    pub files: Vec<PathBuf>,
}
