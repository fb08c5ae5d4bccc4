//! glTF 2.0 scenes (`.gltf` with its buffers, or `.glb`), read into the same groups and materials as an OBJ
//! (`material::Imported`), through the `gltf` crate.
//!
//! What is read, and how it maps onto sensorlight's model (a diffuse `Kd` emitting `Ke`):
//! - the default scene's node tree (else the first scene's), each node's mesh under its world transform
//!   (a transform that mirrors keeps the front counter-clockwise: its triangles' corners are swapped);
//! - each triangle primitive (triangles, strips, fans) as a group, its `NORMAL`s as shading normals (made
//!   unit by the inverse transpose); points and lines are skipped with a warning;
//! - a material's base colour factor as `Kd` (linear RGB) and its base colour texture (`TEXCOORD_0`) as its
//!   colour texture (`Material::kd_map`, as an OBJ's `map_Kd`), its emissive factor times
//!   `KHR_materials_emissive_strength` as `Ke` and its emissive texture (`TEXCOORD_0`) as
//!   `Material::ke_map` (an OBJ's `map_Ke`); `alphaMode` MASK cuts a primitive out where the factor's alpha is
//!   under the cutoff, and with a base colour texture where factor × texture alpha is (`material::Cutout`), BLEND
//!   is drawn opaque (said); other textures, metalness and roughness are named once per material as not
//!   used yet; the glTF default material is white (`Kd` 1);
//! - the first camera met in the tree (perspective), as the scene's camera where the scene file names none;
//! - `KHR_lights_punctual`: a point or spot light becomes a small emitting sphere of 8 × 16 facets
//!   ([`LIGHT_RADIUS`] of the scene's size) whose intensity is the light's (`Ke = 4·I / A`, `A` the facets'
//!   area, a quarter of which is their mean projected area; colour × intensity read as radiometric, W/sr);
//!   a spot's cone is not kept (said); the first directional light is the sun (`scene::sun`: a 0.53° disc
//!   along the node's +z, colour × intensity its irradiance), any other is skipped (said).
//!
//! A file that requires an extension not listed in [`SUPPORTED`] is refused, naming it.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result, bail, ensure};
use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::mesh::Mode;

use super::material::{Group, Imported, Material};
use super::{Camera, Sun};

/// Extensions a file may require.
pub const SUPPORTED: &[&str] = &["KHR_materials_emissive_strength", "KHR_lights_punctual"];

/// A punctual light's sphere: this share of the diagonal of the scene's bounds.
pub const LIGHT_RADIUS: f32 = 0.005;

/// Node instances (a node under each of its parents counts once per path) beyond this are refused: a file
/// whose nodes share children can multiply them without end.
const MAX_INSTANCES: usize = 1 << 20;

/// What a glTF file gives: the groups and materials, and the first camera in its tree.
pub struct GltfData {
    pub mesh: Imported,
    pub camera: Option<Camera>,
    /// The first directional light, as the sun.
    pub sun: Option<Sun>,
}

/// Reads the glTF file at `path`.
///
/// The `gltf` crate indexes its arrays unchecked in places (its own validation does, on a primitive whose
/// `POSITION` names no accessor), so a malformed file can panic inside it: that is caught, kept off stderr,
/// and said as a malformed file (`tests/fuzz_loaders.rs` found it).
pub fn load(path: &Path) -> Result<GltfData> {
    quiet_panics::install();
    let result = std::panic::catch_unwind(|| quiet_panics::silenced(|| read(path)));
    result.unwrap_or_else(|panic| {
        let what = (panic.downcast_ref::<String>().cloned())
            .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
            .unwrap_or_default();
        bail!("{}: not a valid glTF 2.0 file: the glTF reader failed on it ({what})", path.display())
    })
}

/// A panic hook that stays quiet on the threads that ask it to (a parser known to panic on bad input, whose
/// panic is caught and reported as an error), and passes every other panic to the hook it replaced.
mod materials;

mod quiet_panics {
    use std::cell::Cell;
    use std::sync::Once;

    thread_local! {
        static QUIET: Cell<bool> = const { Cell::new(false) };
    }

    pub fn install() {
        static ONCE: Once = Once::new();
        ONCE.call_once(|| {
            let previous = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                if !QUIET.with(Cell::get) {
                    previous(info);
                }
            }));
        });
    }

    /// Runs `work` with this thread's panics kept quiet.
    pub fn silenced<R>(work: impl FnOnce() -> R) -> R {
        struct Reset(bool);
        impl Drop for Reset {
            fn drop(&mut self) {
                QUIET.with(|q| q.set(self.0));
            }
        }
        let _reset = Reset(QUIET.with(|q| q.replace(true)));
        work()
    }
}

/// That `accessor` (`what` for the message) lies within its buffer view and the view within its buffer:
/// `offset + stride · (count − 1) + element size` bytes at most.
fn check_accessor(accessor: &gltf::Accessor<'_>, what: &str, buffers: &[gltf::buffer::Data]) -> Result<()> {
    let Some(view) = accessor.view() else { return Ok(()) }; // all zeros (or sparse): nothing to overrun
    let (count, size) = (accessor.count() as u64, accessor.size() as u64);
    let stride = view.stride().map_or(size, |s| s as u64);
    let needs = accessor.offset() as u64 + stride.saturating_mul(count.saturating_sub(1)) + size;
    let index = accessor.index();
    ensure!(
        count == 0 || needs <= view.length() as u64,
        "malformed: accessor {index} ({what}: {count} elements of {size} bytes, {stride} apart) needs {needs} bytes of \
         buffer view {}, which has {}",
        view.index(),
        view.length()
    );
    let buffer = buffers.get(view.buffer().index()).map_or(0, |b| b.0.len() as u64);
    ensure!(
        (view.offset() + view.length()) as u64 <= buffer,
        "malformed: buffer view {} (of accessor {index}, {what}) ends at byte {}, past its buffer's {buffer}",
        view.index(),
        view.offset() + view.length()
    );
    Ok(())
}

fn read(path: &Path) -> Result<GltfData> {
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let invalid = || format!("{}: not a valid glTF 2.0 file", path.display());
    // The extensions first, so that one sensorlight lacks is named as such rather than as invalid.
    let unchecked = gltf::Gltf::from_slice_without_validation(&bytes).with_context(invalid)?;
    for required in unchecked.extensions_required() {
        ensure!(
            SUPPORTED.contains(&required),
            "{}: requires the glTF extension {required}, which sensorlight does not support (it supports: {})",
            path.display(),
            SUPPORTED.join(", ")
        );
    }
    let gltf = gltf::Gltf::from_slice(&bytes).with_context(invalid)?;
    let base = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone())
        .with_context(|| format!("{}: its buffers", path.display()))?;
    let mut files = vec![path.to_owned()];
    files.extend(gltf.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => Some(base.join(uri)),
        _ => None,
    }));
    files.extend(gltf.images().filter_map(|i| match i.source() {
        gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => Some(base.join(uri)),
        _ => None,
    }));

    let mut reader = Reader {
        path,
        base,
        buffers: &buffers,
        mesh: Imported::default(),
        images: Vec::new(),
        untextured: Vec::new(),
        camera: None,
        sun: None,
        lights: Vec::new(),
        instances: 0,
        material_notes: Vec::new(),
        used_materials: Vec::new(),
    };
    reader.materials(&gltf.document)?;
    let scene = gltf.default_scene().or_else(|| gltf.scenes().next());
    let Some(scene) = scene else { bail!("{}: the file has no scene", path.display()) };
    for node in scene.nodes() {
        reader.node(&node, Mat4::IDENTITY, &mut Vec::new())?;
    }
    reader.punctual_lights();
    for (material, note) in std::mem::take(&mut reader.material_notes) {
        if reader.used_materials[material] {
            reader.warn(note);
        }
    }
    let Reader { mut mesh, camera, sun, .. } = reader;
    mesh.files = dedup(files);
    Ok(GltfData { mesh, camera, sun })
}

fn dedup(mut files: Vec<PathBuf>) -> Vec<PathBuf> {
    let mut seen = std::collections::BTreeSet::new();
    files.retain(|f| seen.insert(f.clone()));
    files
}

struct Reader<'a> {
    path: &'a Path,
    /// Where relative URIs start.
    base: &'a Path,
    buffers: &'a [gltf::buffer::Data],
    mesh: Imported,
    /// Each glTF image read so far: its index in `mesh.textures`, `None` where it could not be read.
    images: Vec<(usize, Option<usize>)>,
    /// Each textured material's copy without its texture, made for a primitive without `TEXCOORD_0`.
    untextured: Vec<(usize, usize)>,
    camera: Option<Camera>,
    sun: Option<Sun>,
    /// Point and spot lights met: position, colour × intensity, and the node's name.
    lights: Vec<(Vec3, Vec3, String)>,
    /// Node instances visited so far ([`MAX_INSTANCES`]).
    instances: usize,
    /// What is said of each material (what of it is not used), once a primitive uses it: a material no
    /// primitive uses is not worth a word.
    material_notes: Vec<(usize, String)>,
    /// The glTF materials primitives use, by index (the default last).
    used_materials: Vec<bool>,
}

impl Reader<'_> {
    fn warn(&mut self, message: String) {
        self.mesh.warnings.push(format!("{}: {message}", self.path.display()));
    }

    /// `node` under `parent`'s transform, below the nodes `ancestors`, then its children.
    fn node(&mut self, node: &gltf::Node, parent: Mat4, ancestors: &mut Vec<usize>) -> Result<()> {
        ensure!(
            !ancestors.contains(&node.index()),
            "{}: node {} is its own ancestor (the node hierarchy loops)",
            self.path.display(),
            node.index()
        );
        self.instances += 1;
        ensure!(
            self.instances <= MAX_INSTANCES,
            "{}: more than {MAX_INSTANCES} node instances (nodes shared by many parents)",
            self.path.display()
        );
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        ensure!(world.is_finite(), "{}: node {} has a transform that is not finite", self.path.display(), node.index());
        if let Some(mesh) = node.mesh() {
            self.mesh_at(&mesh, world)?;
        }
        if let (None, Some(camera)) = (&self.camera, node.camera()) {
            self.camera_at(&camera, world)?;
        }
        if let Some(light) = node.light() {
            let name = node.name().unwrap_or("unnamed").to_owned();
            let power = Vec3::from(light.color()) * light.intensity();
            match light.kind() {
                gltf::khr_lights_punctual::Kind::Directional if self.sun.is_some() => {
                    self.warn(format!("light '{name}': a second directional light; skipped (the first is the sun)"));
                }
                gltf::khr_lights_punctual::Kind::Directional => {
                    // It shines along its node's −z: the sun lies along +z.
                    let towards = world.transform_vector3(Vec3::Z);
                    let sun = Sun::new(towards, Sun::DEFAULT_DIAMETER_DEG, power)
                        .with_context(|| format!("{}: light '{name}'", self.path.display()))?;
                    self.sun = Some(sun);
                }
                kind => {
                    if matches!(kind, gltf::khr_lights_punctual::Kind::Spot { .. }) {
                        self.warn(format!("light '{name}': a spot light's cone is not kept: it lights all around"));
                    }
                    self.lights.push((world.transform_point3(Vec3::ZERO), power, name));
                }
            }
        }
        ancestors.push(node.index());
        for child in node.children() {
            self.node(&child, world, ancestors)?;
        }
        ancestors.pop();
        Ok(())
    }

    fn mesh_at(&mut self, mesh: &gltf::Mesh, world: Mat4) -> Result<()> {
        let mesh_name = mesh.name().map_or_else(|| format!("mesh#{}", mesh.index()), str::to_owned);
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let mirrored = Mat3::from_mat4(world).determinant() < 0.0;
        for primitive in mesh.primitives() {
            let name = format!("{mesh_name}/{}", primitive.index());
            let where_ = || format!("{}: {name}", self.path.display());
            if !matches!(primitive.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                self.warn(format!("{name}: points and lines have no area to light; skipped"));
                continue;
            }
            let material = primitive.material();
            if material.alpha_mode() == gltf::material::AlphaMode::Mask
                && material.pbr_metallic_roughness().base_color_factor()[3] < material.alpha_cutoff().unwrap_or(0.5)
            {
                continue; // cut out entirely
            }
            // The reader answers `None` for an accessor past its buffer view, which reads as a missing
            // attribute: a malformed file is said as such first.
            for (semantic, accessor) in primitive.attributes() {
                check_accessor(&accessor, &format!("{semantic:?}"), self.buffers).with_context(where_)?;
            }
            if let Some(accessor) = primitive.indices() {
                check_accessor(&accessor, "indices", self.buffers).with_context(where_)?;
            }
            let reader = primitive.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(positions) = reader.read_positions() else {
                self.warn(format!("{name}: no POSITION attribute; skipped"));
                continue;
            };
            let positions: Vec<Vec3> = positions.map(|p| world.transform_point3(Vec3::from(p))).collect();
            let normals: Option<Vec<Vec3>> = reader
                .read_normals()
                .map(|n| n.map(|n| (normal_matrix * Vec3::from(n)).try_normalize().unwrap_or(Vec3::ZERO)).collect());
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            if let Some(bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                bail!("{}: index {bad} is beyond its {} vertices", where_(), positions.len());
            }
            if normals.as_ref().is_some_and(|n| n.len() != positions.len()) {
                bail!("{}: NORMAL and POSITION have different counts", where_());
            }
            // The default is last of the file's materials (copies without textures come after it).
            let material_index = material.index().unwrap_or(self.used_materials.len() - 1);
            self.used_materials[material_index] = true;
            let m = &self.mesh.materials[material_index];
            let uvs: Option<Vec<Vec2>> = match m.is_textured() {
                true => reader.read_tex_coords(0).map(|t| t.into_f32().map(Vec2::from).collect()),
                false => None,
            };
            if uvs.as_ref().is_some_and(|t| t.len() != positions.len()) {
                bail!("{}: TEXCOORD_0 and POSITION have different counts", where_());
            }
            // The lightmap's own coordinates, where the file has them (`sensorlight bake`).
            let lightmap_uvs: Option<Vec<Vec2>> =
                reader.read_tex_coords(1).map(|t| t.into_f32().map(Vec2::from).collect());
            if lightmap_uvs.as_ref().is_some_and(|t| t.len() != positions.len()) {
                bail!("{}: TEXCOORD_1 and POSITION have different counts", where_());
            }
            let material_index = match uvs {
                Some(_) => material_index,
                None => self.material_without_coordinates(material_index, &name),
            };
            let corners = triangles(primitive.mode(), &indices);
            let order = |t: [u32; 3]| if mirrored { [t[0], t[2], t[1]] } else { t };
            let group = Group {
                name,
                material: material_index,
                triangles: corners.iter().map(|&t| order(t).map(|i| positions[i as usize])).collect(),
                normals: match &normals {
                    Some(n) => corners.iter().map(|&t| order(t).map(|i| n[i as usize])).collect(),
                    None => Vec::new(),
                },
                uvs: match &uvs {
                    Some(t) => corners.iter().map(|&c| order(c).map(|i| t[i as usize])).collect(),
                    None => Vec::new(),
                },
                lightmap_uvs: match &lightmap_uvs {
                    Some(t) => corners.iter().map(|&c| order(c).map(|i| t[i as usize])).collect(),
                    None => Vec::new(),
                },
            };
            self.mesh.groups.push(group);
        }
        Ok(())
    }

    /// The camera at a node: glTF's looks along its local −z with +y up.
    fn camera_at(&mut self, camera: &gltf::Camera, world: Mat4) -> Result<()> {
        let gltf::camera::Projection::Perspective(p) = camera.projection() else {
            self.warn("an orthographic camera is not supported; the camera frames the mesh instead".into());
            return Ok(());
        };
        let eye = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(-Vec3::Z);
        let up = world.transform_vector3(Vec3::Y);
        let camera = Camera::look_at(eye, eye + forward, up, p.yfov().to_degrees())
            .with_context(|| format!("{}: camera {}", self.path.display(), camera.index()))?;
        self.camera = Some(camera);
        Ok(())
    }

    /// The point and spot lights as small emitting spheres (module docs), sized by the scene's bounds.
    fn punctual_lights(&mut self) {
        if self.lights.is_empty() {
            return;
        }
        let points = self.mesh.groups.iter().flat_map(|g| g.triangles.iter().flatten().copied());
        let bounds = super::Aabb::of(points.chain(self.lights.iter().map(|l| l.0)));
        let radius = (LIGHT_RADIUS * bounds.diagonal()).max(1e-4);
        for (position, power, name) in std::mem::take(&mut self.lights) {
            let (triangles, normals) = sphere(position, radius);
            // A convex body's mean projected area is a quarter of its area (Cauchy): the facets' intensity,
            // averaged over directions, is the light's.
            let area: f32 = triangles.iter().map(super::triangle_area).sum();
            let ke = power * 4.0 / area;
            self.mesh.materials.push(Material::new(&format!("light '{name}'"), Vec3::ZERO, ke));
            let material = self.mesh.materials.len() - 1;
            self.mesh.groups.push(Group {
                name: format!("light '{name}'"),
                material,
                triangles,
                normals,
                uvs: Vec::new(),
                lightmap_uvs: Vec::new(),
            });
        }
    }
}

/// The triangles of a primitive's `indices` in `mode`, each counter-clockwise as glTF orders them (a strip's
/// every other triangle turned back).
fn triangles(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
            .map(|k| {
                let t = [indices[k], indices[k + 1], indices[k + 2]];
                if k % 2 == 0 { t } else { [t[1], t[0], t[2]] }
            })
            .collect(),
        Mode::TriangleFan => {
            (1..indices.len().saturating_sub(1)).map(|k| [indices[0], indices[k], indices[k + 1]]).collect()
        }
        _ => indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}

/// A sphere of 8 × 16 facets, front outwards, with its exact normals at the corners.
fn sphere(centre: Vec3, radius: f32) -> (Vec<[Vec3; 3]>, Vec<[Vec3; 3]>) {
    let (stacks, slices) = (8, 16);
    let direction = |i: usize, j: usize| {
        let (theta, phi) =
            (std::f32::consts::PI * i as f32 / stacks as f32, std::f32::consts::TAU * j as f32 / slices as f32);
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    let mut normals = Vec::new();
    for i in 0..stacks {
        for j in 0..slices {
            let (a, b, c, d) = (direction(i, j), direction(i, j + 1), direction(i + 1, j + 1), direction(i + 1, j));
            if i > 0 {
                normals.push([a, b, c]);
            }
            if i + 1 < stacks {
                normals.push([a, c, d]);
            }
        }
    }
    let triangles = normals.iter().map(|n| n.map(|d| centre + radius * d)).collect();
    (triangles, normals)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_make_counter_clockwise_triangles() {
        assert_eq!(triangles(Mode::TriangleStrip, &[0, 1, 2, 3]), [[0, 1, 2], [2, 1, 3]]);
        assert_eq!(triangles(Mode::TriangleFan, &[0, 1, 2, 3]), [[0, 1, 2], [0, 2, 3]]);
        assert_eq!(triangles(Mode::Triangles, &[0, 1, 2, 3]), [[0, 1, 2]]);
    }

    #[test]
    fn a_light_sphere_faces_out_with_its_exact_normals() {
        let (triangles, normals) = sphere(Vec3::new(1.0, 2.0, 3.0), 0.5);
        assert_eq!(triangles.len(), normals.len());
        for (t, n) in triangles.iter().zip(&normals) {
            let face = (t[1] - t[0]).cross(t[2] - t[0]);
            let centroid = (t[0] + t[1] + t[2]) / 3.0 - Vec3::new(1.0, 2.0, 3.0);
            assert!(face.dot(centroid) > 0.0, "front outwards");
            assert!(n.iter().all(|n| (n.length() - 1.0).abs() < 1e-5 && n.dot(face) > 0.0));
        }
    }
}
