//! Scenes: triangles with materials and surface ids, a camera and an image size. Everything downstream (the
//! GPU passes, the CPU reference) is handed a [`Scene`], never a parser.

pub mod auto_camera;
pub mod builtin;
pub mod bvh;
pub mod camera;
pub mod file;
mod geometry;
pub mod gltf;
pub mod kind;
pub mod material;
mod mesh;
pub mod obj;
pub mod path;
pub mod ray;
pub mod sky;
mod sky_sun;
pub mod sun;
pub mod surfaces;
pub mod texture;
mod unrendered;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context as _, Result, bail, ensure};
use glam::Vec3;

pub use camera::Camera;
pub use geometry::{
    Aabb, NO_SURFACE, SurfaceId, Triangle, at_barycentric, barycentric, closest_on_triangle, interpolate,
    stratified_point, subdivision, subdivision_centroids, triangle_area,
};
pub use kind::FileKind;
pub use material::Material;
pub use mesh::{MAX_EMITTER_SPLIT, MAX_TEXTURED_EMITTER_PARTS, Mesh, Surface};
pub use path::CameraPath;
pub use ray::Ray;
pub use sky::SkyMap;
pub use sun::Sun;
pub use texture::Texture;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ImageSize {
    pub width: u32,
    pub height: u32,
}

#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file it came from, for messages.
    pub path: PathBuf,
    pub mesh: Mesh,
    pub camera: Camera,
    pub image: ImageSize,
    /// The scene file's `[render]` table, uninterpreted (read by `params::Overrides::from_scene_table`).
    pub render: toml::Table,
    /// The sun, whose disc is the mesh's last surface (`Mesh::add_sun`).
    pub sun: Option<Sun>,
    /// The environment map rays that leave the scene see (`scene::sky`); none: the constant background.
    pub sky: Option<Arc<SkyMap>>,
    /// Warnings met while loading (undefined materials, dropped triangles, no emitter, `Kd` above 1, …).
    pub warnings: Vec<String>,
    /// What a user should know that is not a problem (where the automatic camera was put, and why).
    pub notes: Vec<String>,
    /// The files it was read from: the scene file, the mesh, its material libraries (none when built in).
    /// Outputs must not overwrite them.
    pub inputs: Vec<PathBuf>,
    /// The OBJ file the mesh came from (none when built in).
    pub mesh_file: Option<PathBuf>,
    /// The scene file's camera path (`[path]`), for the frames of a fly-through.
    pub camera_path: Option<CameraPath>,
}

impl Scene {
    /// [`Scene::inputs`] as paths.
    pub fn input_paths(&self) -> Vec<&Path> {
        self.inputs.iter().map(PathBuf::as_path).collect()
    }

    /// Reads a TOML scene file and the mesh it names; the camera is the file's `[camera]`, else a glTF mesh's
    /// first. Errors name the file and, where known, the line; a file of another kind (a mesh, an image) is
    /// named as such.
    pub fn load(path: &Path) -> Result<Self> {
        match FileKind::of(path) {
            FileKind::Scene => {}
            kind => bail!("{} is {}, not a scene file (TOML)", path.display(), kind.describe()),
        }
        let file = file::SceneFile::read(path)?;
        let camera = match &file.camera {
            Some(c) => Some(
                Camera::look_at(c.eye.into(), c.target.into(), c.up.into(), c.vfov_deg)
                    .with_context(|| format!("{}: [camera]", path.display()))?,
            ),
            None => None,
        };
        let image = ImageSize { width: file.image.width, height: file.image.height };
        ensure!(
            image.width >= 1 && image.height >= 1,
            "{}: [image] width and height must be at least 1",
            path.display()
        );
        let mesh_path = file.mesh_path(path);
        let (obj, file_camera, file_sun) = read_mesh(&mesh_path)?;
        // The scene file's camera, else the glTF's first.
        let Some(camera) = camera.or(file_camera) else {
            bail!(
                "{}: no [camera] table, and its mesh {} has no camera to take instead (a glTF file may have one; \
                 an OBJ never does)",
                path.display(),
                mesh_path.display()
            );
        };
        let camera_path = match &file.path {
            Some(p) => Some(CameraPath::new(p, &camera).with_context(|| format!("{}: [path]", path.display()))?),
            None => None,
        };
        let sun = match &file.sun {
            Some(s) => Some(
                Sun::new(
                    s.direction.into(),
                    s.angular_diameter_deg.unwrap_or(Sun::DEFAULT_DIAMETER_DEG),
                    s.irradiance.map_or(Vec3::splat(Sun::DEFAULT_IRRADIANCE), |c| c.rgb().into()),
                )
                .with_context(|| format!("{}: [sun]", path.display()))?,
            ),
            None => file_sun,
        };
        let sky = match &file.sky {
            Some(s) => {
                let map = file.relative_path(path, &s.map);
                let sky = SkyMap::load(&map, s.strength.unwrap_or(1.0))
                    .and_then(|sky| sky.turned(s.rotation_deg.unwrap_or(0.0)))
                    .with_context(|| format!("{}: [sky]", path.display()))?;
                Some(sky)
            }
            None => None,
        };
        let mut warnings = obj.warnings;
        let mut mesh = Mesh::new(&obj.groups, obj.materials, obj.textures, &mut warnings)
            .with_context(|| mesh_path.display().to_string())?;
        if let Some(sun) = &sun {
            mesh.add_sun(sun);
        }
        warnings.extend(mesh.lighting_warnings());
        let mut inputs = vec![path.to_owned()];
        inputs.extend(obj.files);
        let mesh_file = Some(mesh_path);
        let mut scene = Self {
            path: path.to_owned(),
            mesh,
            camera,
            image,
            render: file.render,
            sun,
            sky: None,
            warnings,
            notes: Vec::new(),
            inputs,
            mesh_file,
            camera_path,
        };
        if let Some(sky) = sky {
            scene.set_sky(sky).with_context(|| format!("{}: [sky]", path.display()))?;
        }
        Ok(scene)
    }
}

/// The groups and materials of the mesh file at `path`, by its kind (glTF, else OBJ), and a glTF's first
/// camera and sun.
fn read_mesh(path: &Path) -> Result<(material::Imported, Option<Camera>, Option<Sun>)> {
    match FileKind::of(path) {
        FileKind::GltfMesh => gltf::load(path).map(|g| (g.mesh, g.camera, g.sun)),
        _ => Ok((obj::load(path)?, None, None)),
    }
}

impl Scene {
    /// A scene of the mesh at `path` alone (OBJ or glTF): the glTF's first camera, else one that frames it
    /// ([`auto_camera`]); the image is `image`, and the `[render]` table is empty (the defaults).
    pub fn from_mesh(path: &Path, image: ImageSize) -> Result<Self> {
        ensure!(image.width >= 1 && image.height >= 1, "image width and height must be at least 1");
        let (obj, file_camera, sun) = read_mesh(path)?;
        let mut warnings = obj.warnings;
        let mut mesh = Mesh::new(&obj.groups, obj.materials, obj.textures, &mut warnings)
            .with_context(|| path.display().to_string())?;
        // The camera frames the mesh itself, before the sun's far disc joins it.
        let (camera, placement) = match file_camera {
            Some(camera) => (camera, auto_camera::Placement::Outside),
            None => auto_camera::for_mesh(&mesh, image).with_context(|| format!("{}: camera", path.display()))?,
        };
        if let Some(sun) = &sun {
            mesh.add_sun(sun);
        }
        warnings.extend(mesh.lighting_warnings());
        let mut notes = Vec::new();
        if placement == auto_camera::Placement::Inside {
            let f = camera.forward;
            notes.push(format!(
                "{} encloses its centre and its light: the camera is inside, at {}, looking along ({}, {}, {}) \
                 (--write-scene writes the scene to edit)",
                path.display(),
                camera.eye,
                f.x,
                f.y,
                f.z
            ));
        }
        let render = toml::Table::new();
        let mesh_file = Some(path.to_owned());
        let inputs = obj.files;
        Ok(Self {
            path: path.to_owned(),
            mesh,
            camera,
            image,
            render,
            sun,
            sky: None,
            warnings,
            notes,
            inputs,
            mesh_file,
            camera_path: None,
        })
    }

    /// Lights the scene with `sun`, in place of its own if it has one (warnings about the light said again).
    pub fn set_sun(&mut self, sun: Sun) {
        if self.sun.is_some() {
            self.mesh.remove_sun();
        }
        self.mesh.add_sun(&sun);
        self.sun = Some(sun);
        self.warnings.retain(|w| w != Mesh::NO_EMITTER);
    }

    /// Lights the scene with the environment map `sky` (in place of its own, if any): rays that leave the
    /// scene see it instead of the constant background. Its file joins the inputs no output may overwrite.
    ///
    /// A sun painted into the map is taken out of it and drawn as the scene's sun (`scene::sky_sun`), unless
    /// the scene has a sun of its own: then the map's stays in the map, said. A sun taken out of the map
    /// this one replaces goes with it.
    pub fn set_sky(&mut self, sky: SkyMap) -> Result<()> {
        if self.sun_from_sky() {
            self.mesh.remove_sun();
            self.sun = None;
        }
        if let Some(old) = self.sky.take() {
            let old_path = PathBuf::from(&old.name);
            self.inputs.retain(|p| *p != old_path);
        }
        let sky = match self.sun {
            None => sky.without_sun()?,
            Some(_) => {
                if let Some((painted, _)) = sky.painted_sun()? {
                    self.warnings.push(format!(
                        "sky map {} holds a sun ({:.2}° wide, irradiance {:.3}) but the scene has a sun of its own: \
                         the map's stays in the map, where the sensors blur it; give the scene no [sun] to have it \
                         drawn as the sun",
                        sky.name,
                        painted.angular_diameter_deg,
                        painted.irradiance.max_element()
                    ));
                }
                sky
            }
        };
        if let Some(sun) = sky.taken_sun {
            let d = sun.direction;
            self.notes.push(format!(
                "sky map {}: its sun ({:.2}° wide, towards ({:.3}, {:.3}, {:.3}), irradiance {:.3} {:.3} {:.3}) is \
                 drawn as the scene's sun, the map around it keeping the sky",
                sky.name, sun.angular_diameter_deg, d.x, d.y, d.z, sun.irradiance.x, sun.irradiance.y, sun.irradiance.z
            ));
            self.set_sun(sun);
        }
        self.inputs.push(PathBuf::from(&sky.name));
        self.sky = Some(Arc::new(sky));
        self.warnings.retain(|w| w != Mesh::NO_EMITTER);
        Ok(())
    }

    /// Whether the scene's sun is the one taken out of its sky map ([`SkyMap::taken_sun`]).
    fn sun_from_sky(&self) -> bool {
        self.sky.as_ref().is_some_and(|s| s.taken_sun.is_some() && s.taken_sun == self.sun)
    }

    /// This scene as a TOML scene file to be written at `toml_path`: the mesh relative to that file's
    /// directory where it lies below it (else absolute), the camera, the image size and the `[render]` table.
    pub fn to_toml(&self, toml_path: &Path) -> Result<String> {
        self.to_toml_with(toml_path, &self.render)
    }

    /// [`Scene::to_toml`] with `render` as its `[render]` table (what a render resolved, e.g. its automatic
    /// exposure, so that the scene file renders as the mesh did).
    pub fn to_toml_with(&self, toml_path: &Path, render: &toml::Table) -> Result<String> {
        let Some(mesh_path) = &self.mesh_file else { bail!("a built-in scene has no mesh file to name") };
        let dir = toml_path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let mesh = std::fs::canonicalize(mesh_path).with_context(|| mesh_path.display().to_string())?;
        let mesh = match std::fs::canonicalize(dir) {
            Ok(dir) => mesh.strip_prefix(&dir).map(Path::to_owned).unwrap_or(mesh),
            Err(_) => mesh,
        };
        let c = &self.camera;
        // f32 → f64 by the shortest text that reads back as the f32: 0.1, not 0.10000000149011612.
        let num = |v: f32| toml::Value::Float(v.to_string().parse().unwrap_or(v as f64));
        let vec = |v: Vec3| toml::Value::Array(v.to_array().map(num).to_vec());
        let mut camera = toml::Table::new();
        camera.insert("eye".into(), vec(c.eye));
        // A camera inside the mesh stands at its centre: its target is then a tenth of the scene ahead.
        let reach = (self.mesh.bounds.center() - c.eye).length().max(0.1 * self.mesh.scale());
        camera.insert("target".into(), vec(c.eye + c.forward * reach));
        camera.insert("up".into(), vec(c.up));
        // Degrees → radians → degrees drifts in the last bit (40 → 40.000004): four decimals are plenty.
        camera.insert("vfov_deg".into(), num((c.vfov.to_degrees() * 1e4).round() / 1e4));
        let mut image = toml::Table::new();
        image.insert("width".into(), toml::Value::Integer(self.image.width.into()));
        image.insert("height".into(), toml::Value::Integer(self.image.height.into()));
        let mut doc = toml::Table::new();
        let mesh = mesh.to_str().with_context(|| format!("{}: not UTF-8", mesh.display()))?;
        doc.insert("mesh".into(), toml::Value::String(mesh.to_owned()));
        doc.insert("camera".into(), toml::Value::Table(camera));
        doc.insert("image".into(), toml::Value::Table(image));
        // A sun taken out of the sky map is the map's: written as a [sun], it would keep the map's in the map.
        if let Some(sun) = self.sun.as_ref().filter(|_| !self.sun_from_sky()) {
            let mut table = toml::Table::new();
            table.insert("direction".into(), vec(sun.direction));
            table.insert("irradiance".into(), vec(sun.irradiance));
            table.insert("angular_diameter_deg".into(), num(sun.angular_diameter_deg));
            doc.insert("sun".into(), toml::Value::Table(table));
        }
        if let Some(sky) = &self.sky {
            let map = std::fs::canonicalize(&sky.name).with_context(|| sky.name.clone())?;
            let map = match std::fs::canonicalize(dir) {
                Ok(dir) => map.strip_prefix(&dir).map(Path::to_owned).unwrap_or(map),
                Err(_) => map,
            };
            let mut table = toml::Table::new();
            let map = map.to_str().with_context(|| format!("{}: not UTF-8", map.display()))?;
            table.insert("map".into(), toml::Value::String(map.to_owned()));
            table.insert("strength".into(), num(sky.strength));
            table.insert("rotation_deg".into(), num(sky.rotation_deg));
            doc.insert("sky".into(), toml::Value::Table(table));
        }
        if let Some(path) = &self.camera_path {
            // Every key whole (its up and field of view too), so that it reads back whatever [camera] is.
            let keys = (path.keys.iter())
                .map(|k| {
                    let mut key = toml::Table::new();
                    key.insert("time".into(), num(k.time));
                    key.insert("eye".into(), vec(k.eye));
                    key.insert("target".into(), vec(k.target));
                    key.insert("up".into(), vec(k.up));
                    key.insert("vfov_deg".into(), num(k.vfov_deg));
                    toml::Value::Table(key)
                })
                .collect();
            let mut table = toml::Table::new();
            table.insert("fps".into(), num(path.fps));
            table.insert("key".into(), toml::Value::Array(keys));
            doc.insert("path".into(), toml::Value::Table(table));
        }
        if !render.is_empty() {
            doc.insert("render".into(), toml::Value::Table(render.clone()));
        }
        let body = toml::to_string(&doc).context("scene to TOML")?;
        Ok(format!(
            "# A scene for {}, written by sensorlight: edit freely (see docs/USAGE.md, Scenes).\n{body}",
            self.path.display()
        ))
    }
}
