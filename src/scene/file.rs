//! The TOML scene file: which mesh, the camera, the image size and optional defaults for the algorithm.
//!
//! ```toml
//! mesh = "cornell.obj"          # relative to the TOML file
//! [camera]                     # optional with a glTF mesh that has one
//! eye = [278, 273, -800]
//! target = [278, 273, 0]
//! up = [0, 1, 0]
//! vfov_deg = 39.3               # full vertical angle
//! [image]
//! width = 256
//! height = 256
//! [sun]                         # optional: a distant disc lighting the scene (scene::sun)
//! direction = [0.3, 1, 0.2]     # towards the sun
//! irradiance = 3.14             # or [r, g, b]; on a surface facing it (default π)
//! angular_diameter_deg = 0.53   # the default
//! [sky]                         # optional: an environment map (scene::sky) in place of the background
//! map = "sky.exr"               # equirectangular, linear radiance (OpenEXR or Radiance HDR), +y up
//! strength = 1.0                # its texels are multiplied by this (default 1)
//! rotation_deg = 0              # turned about +y, counter-clockwise seen from above (default 0)
//! [path]                        # optional: a camera path, keyframes with times (scene::path)
//! fps = 24
//! [[path.key]]
//! time = 0
//! eye = [278, 273, -800]
//! target = [278, 273, 0]
//! [render]                      # optional; every key is also a CLI flag, which wins
//! sensor = "hemicube"           # or "frustum"
//! ```
//! Unknown keys are errors (a typo must not silently fall back to a default). The `[render]` table is kept
//! as written: the scene knows no render parameter; `params::Overrides` reads and checks it.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use serde::Deserialize;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// The mesh (OBJ or glTF), relative to the TOML file.
    pub mesh: PathBuf,
    /// Optional where the mesh is a glTF file with a camera (its first is taken).
    pub camera: Option<CameraSection>,
    pub image: ImageSection,
    pub sun: Option<SunSection>,
    pub sky: Option<SkySection>,
    /// A camera path for the frames of a fly-through (`scene::path`).
    pub path: Option<super::path::PathSection>,
    /// Render parameters for this scene, uninterpreted here.
    #[serde(default)]
    pub render: toml::Table,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    pub vfov_deg: f32,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunSection {
    pub direction: [f32; 3],
    pub irradiance: Option<Colour>,
    pub angular_diameter_deg: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkySection {
    /// The map, relative to the TOML file.
    pub map: PathBuf,
    pub strength: Option<f32>,
    pub rotation_deg: Option<f32>,
}

/// A colour written as one number (grey) or three.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(untagged)]
pub enum Colour {
    Grey(f32),
    Rgb([f32; 3]),
}

impl Colour {
    pub fn rgb(self) -> [f32; 3] {
        match self {
            Self::Grey(v) => [v; 3],
            Self::Rgb(rgb) => rgb,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageSection {
    pub width: u32,
    pub height: u32,
}

impl SceneFile {
    pub fn read(path: &Path) -> Result<Self> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("cannot read scene file {}", path.display()))?;
        // toml's message already names the line and column and quotes the offending text.
        toml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    }

    /// The mesh path resolved against the directory of the scene file.
    pub fn mesh_path(&self, scene_path: &Path) -> PathBuf {
        self.relative_path(scene_path, &self.mesh)
    }

    /// `path` as written in the file at `scene_path`: relative to that file's directory.
    pub fn relative_path(&self, scene_path: &Path, path: &Path) -> PathBuf {
        scene_path.parent().unwrap_or(Path::new(".")).join(path)
    }
}
