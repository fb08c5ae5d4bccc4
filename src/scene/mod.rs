//! Scenes: triangles with materials and surface ids, a camera and an image size. Everything downstream (the
//! GPU passes, the CPU reference) is handed a [`Scene`], never a parser.

pub mod auto_camera;
pub mod builtin;
pub mod bvh;
pub mod camera;
pub mod file;
pub mod gltf;
pub mod kind;
pub mod material;
pub mod obj;
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
use glam::{Vec2, Vec3};

pub use camera::Camera;
pub use kind::FileKind;
pub use material::Material;
pub use ray::Ray;
pub use sky::SkyMap;
pub use sun::Sun;
pub use texture::Texture;

/// Most parts of all emission-textured triangles together ([`Mesh::emitter_split`]): each part is an emitter
/// that every sensor's exact emitter term sums.
pub const MAX_TEXTURED_EMITTER_PARTS: usize = 4096;

/// Most parts a side of one emission-textured triangle is cut into ([`Mesh::emitter_parts`]): 8 × 8 parts
/// measured within 0.4 % of the oracle on a 4 × 4-texel panel.
pub const MAX_EMITTER_SPLIT: usize = 8;

/// Surface ids are 1-based; 0 marks "no surface" (the background) in the G-buffer.
pub type SurfaceId = u32;
pub const NO_SURFACE: SurfaceId = 0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Counter-clockwise seen from the front.
    pub v: [Vec3; 3],
    /// Unit normal of the front side: normalize((v1 − v0) × (v2 − v0)).
    pub normal: Vec3,
    pub surface: SurfaceId,
}

/// A surface: the triangles of one group and material that form one connected, nearly flat patch. The
/// refinement and the filter never mix two surfaces (paper §III-G, §III-H).
#[derive(Clone, Debug)]
pub struct Surface {
    /// "group/material", for messages and AOV legends.
    pub name: String,
    pub material: usize,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Self = Self { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(self, other: Self) -> Self {
        Self { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The box of `points` ([`Aabb::EMPTY`] for none).
    pub fn of(points: impl IntoIterator<Item = Vec3>) -> Self {
        let mut b = Self::EMPTY;
        points.into_iter().for_each(|p| b.grow(p));
        b
    }

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    /// Whether it holds `other`.
    pub fn contains(&self, other: &Self) -> bool {
        self.min.cmple(other.min).all() && other.max.cmple(self.max).all()
    }

    /// The distance from `p` to its nearest point (0 inside). Where one box holds another, this is never
    /// larger for it, in floating point too (every step is monotonic).
    pub fn distance(&self, p: Vec3) -> f32 {
        (self.min - p).max(p - self.max).max(Vec3::ZERO).length()
    }

    /// The distance from `p` to its farthest point.
    pub fn farthest(&self, p: Vec3) -> f32 {
        (p - self.min).abs().max((p - self.max).abs()).length()
    }
}

#[derive(Clone, Debug)]
pub struct Mesh {
    pub triangles: Vec<Triangle>,
    /// Each triangle's corners' shading normals (unit, on its front's side), interpolated across it for
    /// shading ([`Mesh::shading_normal`]); empty where the mesh gives none: flat, the front normal.
    pub shading: Vec<[Vec3; 3]>,
    /// Each triangle's corners' texture coordinates ((0, 0): the image's top-left corner); empty where no
    /// material has a texture.
    pub uvs: Vec<[Vec2; 3]>,
    /// Indexed by `SurfaceId - 1`.
    pub surfaces: Vec<Surface>,
    pub materials: Vec<Material>,
    /// The textures the materials name (`Material::kd_map`, `Cutout::map`); shared with the BVH.
    pub textures: std::sync::Arc<Vec<Texture>>,
    /// Each surface's mean colour of its texture (1 without one), which its `Kd` multiplies
    /// ([`Mesh::surface_albedo`]); indexed by `SurfaceId - 1`.
    pub texture_mean: Vec<Vec3>,
    pub bounds: Aabb,
}

impl Mesh {
    /// Builds the mesh from groups of triangles, dropping degenerate ones and assigning surface ids.
    /// `warnings` receives what was dropped.
    pub fn new(
        groups: &[material::Group],
        materials: Vec<Material>,
        textures: Vec<Texture>,
        warnings: &mut Vec<String>,
    ) -> Result<Self> {
        let surfaces::Assigned { triangles, normals: shading, uvs, surfaces, dropped } =
            surfaces::assign(groups, &materials);
        if let Some((group, v)) = &dropped.first_not_finite {
            bail!(
                "{} triangle(s) with a corner that is not a finite number (the first, in group '{group}': {}, {}, \
                 {})",
                dropped.not_finite,
                v[0],
                v[1],
                v[2]
            );
        }
        if let Some((group, v)) = &dropped.first_overflowing {
            bail!(
                "{} triangle(s) too large for 32-bit floats: their area overflows (the first, in group '{group}': \
                 {}, {}, {}); scale the mesh down",
                dropped.overflowing,
                v[0],
                v[1],
                v[2]
            );
        }
        let degenerate = dropped.degenerate;
        if degenerate > 0 {
            warnings.push(format!("dropped {degenerate} degenerate (zero-area) triangle(s)"));
        }
        ensure!(
            !triangles.is_empty(),
            "the mesh contains no triangles{}",
            if degenerate > 0 { format!(" of non-zero area ({degenerate} degenerate)") } else { String::new() }
        );
        let mut bounds = Aabb::EMPTY;
        for t in &triangles {
            t.v.iter().for_each(|&p| bounds.grow(p));
        }
        // Offsets and near planes are fractions of the diagonal: it must be a finite f32.
        ensure!(
            bounds.diagonal().is_finite(),
            "the mesh spans {} to {}, too large for 32-bit floats; scale it down",
            bounds.min,
            bounds.max
        );
        let textures = std::sync::Arc::new(textures);
        let mut mesh =
            Self { triangles, shading, uvs, surfaces, materials, textures, texture_mean: Vec::new(), bounds };
        mesh.texture_mean = mesh.texture_means();
        Ok(mesh)
    }

    /// The albedo at `p` on triangle `triangle`: `Kd`, times its texture at `p` (full resolution) where the
    /// material has one.
    pub fn albedo_at(&self, triangle: usize, p: Vec3) -> Vec3 {
        let material = self.material_of(self.triangles[triangle].surface);
        self.texel_or(material.kd, triangle, material.kd_map, p)
    }

    /// The radiance triangle `triangle` emits at `p` (front side): `Ke`, times its emission texture at `p`
    /// (full resolution) where the material has one.
    pub fn emission_at(&self, triangle: usize, p: Vec3) -> Vec3 {
        let material = self.material_of(self.triangles[triangle].surface);
        self.texel_or(material.ke, triangle, material.ke_map, p)
    }

    /// `factor` times texture `map`'s texel at `p` on triangle `triangle` (bilinear, full resolution), or
    /// `factor` alone where the material names no texture or the mesh places none.
    fn texel_or(&self, factor: Vec3, triangle: usize, map: Option<usize>, p: Vec3) -> Vec3 {
        match self.texture_at(triangle, map) {
            Some((texture, uvs)) => {
                factor * texture.sample(interpolate(&self.triangles[triangle].v, uvs, p), 0.0).truncate()
            }
            None => factor,
        }
    }

    /// Texture `map` of triangle `triangle` and its corners' coordinates, where both exist.
    fn texture_at(&self, triangle: usize, map: Option<usize>) -> Option<(&Texture, &[Vec2; 3])> {
        Some((&self.textures[map?], self.uvs.get(triangle)?))
    }

    /// Whether triangle `triangle` emits through a texture: its radiance varies over it.
    pub fn emits_textured(&self, triangle: usize) -> bool {
        let material = self.material_of(self.triangles[triangle].surface);
        material.is_emitter() && self.texture_at(triangle, material.ke_map).is_some()
    }

    /// The mean radiance triangle `triangle` emits: `Ke` times its texture's mean over it.
    pub fn mean_emission(&self, triangle: usize) -> Vec3 {
        let material = self.material_of(self.triangles[triangle].surface);
        match self.texture_at(triangle, material.ke_map) {
            Some((texture, uvs)) => material.ke * texture.mean_over(uvs).truncate(),
            None => material.ke,
        }
    }

    /// The most parts a side of an emission-textured triangle is cut into ([`Mesh::emitter_parts`]): as many
    /// as keep all such triangles' parts within [`MAX_TEXTURED_EMITTER_PARTS`], at most [`MAX_EMITTER_SPLIT`].
    pub fn emitter_split(&self) -> usize {
        let textured = (0..self.triangles.len()).filter(|&i| self.emits_textured(i)).count();
        let split = (MAX_TEXTURED_EMITTER_PARTS as f64 / textured.max(1) as f64).sqrt().floor() as usize;
        split.clamp(1, MAX_EMITTER_SPLIT)
    }

    /// Emitting triangle `triangle` as the exact emitter term sees it (docs/DESIGN.md §1): itself with `Ke`
    /// when its radiance is constant; with an emission texture, its k × k subdivision, each part emitting
    /// its texture's mean over it, k about twice the texels a side of it covers, at most `max_split`. The
    /// irradiance of a constant-radiance polygon is exact in closed form; splitting makes the texture's
    /// variation over the emitter piecewise constant at about half a texel, which measured within 1 % of
    /// the oracle (docs/ACCURACY.md, "Emission textures").
    pub fn emitter_parts(&self, triangle: usize, max_split: usize) -> Vec<([Vec3; 3], Vec3)> {
        let t = &self.triangles[triangle];
        let material = self.material_of(t.surface);
        let Some((texture, uvs)) = self.texture_at(triangle, material.ke_map) else {
            return vec![(t.v, material.ke)];
        };
        let k = (2.0 * texture.footprint(uvs).sqrt()).ceil() as usize;
        subdivision(k.clamp(1, max_split.max(1)))
            .map(|b| {
                let part_uvs = b.map(|b| at_barycentric(uvs, b));
                (b.map(|b| at_barycentric(&t.v, b)), material.ke * texture.mean_over(&part_uvs).truncate())
            })
            .collect()
    }

    /// Adds the sun's disc (`scene::sun`) after the mesh's own triangles, as one surface of its own
    /// material; the bounds stay the scene's own.
    pub fn add_sun(&mut self, sun: &Sun) {
        let (facets, radiance) = sun.facets(&self.bounds);
        let material = Material::new("sun", Vec3::ZERO, radiance);
        self.materials.push(material);
        self.surfaces.push(Surface { name: "sun/sun".into(), material: self.materials.len() - 1 });
        self.texture_mean.push(Vec3::ONE);
        let surface = self.surfaces.len() as SurfaceId;
        for v in facets {
            let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
            self.triangles.push(Triangle { v, normal, surface });
            if !self.shading.is_empty() {
                self.shading.push([normal; 3]);
            }
            if !self.uvs.is_empty() {
                self.uvs.push([Vec2::ZERO; 3]);
            }
        }
    }

    /// Removes the sun [`Mesh::add_sun`] added: its triangles, surface and material, the last of each.
    fn remove_sun(&mut self) {
        let local = self.local_triangles().len();
        self.triangles.truncate(local);
        self.shading.truncate(if self.shading.is_empty() { 0 } else { local });
        self.uvs.truncate(if self.uvs.is_empty() { 0 } else { local });
        self.surfaces.pop();
        self.texture_mean.pop();
        self.materials.pop();
    }

    /// The mesh's own triangles: all but the distant lights' ([`Mesh::add_sun`]), which come after them
    /// and lie outside its bounds (the radiance cache covers these only).
    pub fn local_triangles(&self) -> &[Triangle] {
        let inside = |t: &&Triangle| t.v.iter().all(|&p| self.bounds.contains(&Aabb { min: p, max: p }));
        let local = self.triangles.iter().take_while(inside).count();
        &self.triangles[..local]
    }

    /// Whether a material has a texture (colour, emission or cut-out) that the mesh's texture coordinates
    /// place.
    pub fn has_textures(&self) -> bool {
        !self.uvs.is_empty() && self.materials.iter().any(Material::is_textured)
    }

    /// Whether a material has a cut-out (`Material::cutout`) that the mesh's texture coordinates place.
    pub fn has_cutouts(&self) -> bool {
        !self.uvs.is_empty() && self.materials.iter().any(|m| m.cutout.is_some())
    }

    /// The mean albedo over surface `surface`: what the radiance cache's pieces reflect onwards, and what
    /// the sensor maps scale to the texel's (docs/DESIGN.md §1); `Kd` where it has no texture.
    pub fn surface_albedo(&self, surface: SurfaceId) -> Vec3 {
        self.material_of(surface).kd * self.texture_mean[surface as usize - 1]
    }

    /// [`Mesh::texture_mean`] of every surface: each textured triangle's mean ([`Texture::mean_over`]),
    /// weighted by area.
    fn texture_means(&self) -> Vec<Vec3> {
        let mut sums = vec![(Vec3::ZERO, 0.0f32); self.surfaces.len()];
        for (i, t) in self.triangles.iter().enumerate() {
            let material = self.material_of(t.surface);
            let Some((texture, uv)) = self.texture_at(i, material.kd_map) else { continue };
            let area = triangle_area(&t.v);
            let s = &mut sums[t.surface as usize - 1];
            s.0 += texture.mean_over(uv).truncate() * area;
            s.1 += area;
        }
        sums.into_iter().map(|(sum, area)| if area > 0.0 { sum / area } else { Vec3::ONE }).collect()
    }

    /// Each corner's texture coordinates of every triangle, three per triangle in order: what the G-buffer
    /// interpolates ((0, 0) on a mesh without textures).
    pub fn corner_uvs(&self) -> impl Iterator<Item = Vec2> + '_ {
        (0..self.triangles.len()).flat_map(|i| self.uvs.get(i).copied().unwrap_or([Vec2::ZERO; 3]))
    }

    /// The shading normal at `p` on triangle `triangle` (front side): the corners' shading normals
    /// interpolated by `p`'s barycentric coordinates and normalised; the front normal on a flat mesh.
    pub fn shading_normal(&self, triangle: usize, p: Vec3) -> Vec3 {
        let t = &self.triangles[triangle];
        let Some(corners) = self.shading.get(triangle) else { return t.normal };
        interpolate(&t.v, corners, p).try_normalize().unwrap_or(t.normal)
    }

    /// Each corner's shading normal of every triangle, three per triangle in order: what the G-buffer
    /// interpolates (the front normal thrice on a flat mesh).
    pub fn corner_normals(&self) -> impl Iterator<Item = Vec3> + '_ {
        (self.triangles.iter().enumerate()).flat_map(|(i, t)| self.shading.get(i).copied().unwrap_or([t.normal; 3]))
    }

    /// Warnings about the light in the scene, each naming what it is about: no surface emits (the image is
    /// then black at ε = 0 with a black background), or a material in use reflects more than it receives
    /// (`Kd` above 1: energy gain).
    pub fn lighting_warnings(&self) -> Vec<String> {
        let mut used: Vec<usize> = self.surfaces.iter().map(|s| s.material).collect();
        used.sort_unstable();
        used.dedup();
        let mut warnings = Vec::new();
        if !self.emits_light() {
            warnings.push(Self::NO_EMITTER.to_owned());
        }
        for m in used.iter().map(|&m| &self.materials[m]) {
            if m.kd.max_element() > 1.0 {
                warnings.push(format!(
                    "material '{}' has {} {} {} {}, above 1: it reflects more light than it receives (energy gain)",
                    m.name,
                    m.format.albedo_word(),
                    m.kd.x,
                    m.kd.y,
                    m.kd.z
                ));
            }
        }
        warnings
    }

    /// The largest `Ke` component of the materials in use (0 without emitters).
    pub fn brightest_emission(&self) -> f32 {
        self.surfaces.iter().map(|s| self.materials[s.material].ke.max_element()).fold(0.0, f32::max)
    }

    /// The warning [`Mesh::lighting_warnings`] gives when no surface emits.
    pub const NO_EMITTER: &str = "no surface emits light (no material in use has Ke > 0): the image shows only \
                                  Kd·ε and the background, and is black at ε = 0 with a black background";

    /// Whether a material in use emits light.
    pub fn emits_light(&self) -> bool {
        self.surfaces.iter().any(|s| self.materials[s.material].is_emitter())
    }

    pub fn material_of(&self, surface: SurfaceId) -> &Material {
        &self.materials[self.surfaces[surface as usize - 1].material]
    }

    /// Scene scale: sensors are lifted and near planes placed relative to this length.
    pub fn scale(&self) -> f32 {
        self.bounds.diagonal().max(f32::MIN_POSITIVE)
    }
}

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

/// The corners' `values` of triangle `v` (shading normals, texture coordinates) interpolated at `p` by its
/// [`barycentric`] coordinates.
pub fn interpolate<T>(v: &[Vec3; 3], values: &[T; 3], p: Vec3) -> T
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let [b0, b1, b2] = barycentric(v, p);
    values[0] * b0 + values[1] * b1 + values[2] * b2
}

/// The point of barycentric coordinates `(b.x, b.y)` (the weights of corners 1 and 2) among `values`.
pub fn at_barycentric<T>(values: &[T; 3], b: Vec2) -> T
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    values[0] * (1.0 - b.x - b.y) + values[1] * b.x + values[2] * b.y
}

/// A triangle's k × k subdivision: k² congruent triangles, each as its corners' barycentric coordinates
/// (weights of corners 1 and 2), counter-clockwise as the triangle is; together they tile it.
///
/// ```text
///   corner 2
///     |\
///     |\|\        k = 3: the upright triangles at (a, b), a + b < k, and the
///     |\|\|\       inverted ones between them, a + b + 1 < k
///   corner 0 ── corner 1
/// ```
pub fn subdivision(k: usize) -> impl Iterator<Item = [Vec2; 3]> {
    let s = 1.0 / k as f32;
    (0..k).flat_map(move |a| {
        (0..k - a).flat_map(move |b| {
            let at = |i: usize, j: usize| Vec2::new(i as f32 * s, j as f32 * s);
            let upright = [at(a, b), at(a + 1, b), at(a, b + 1)];
            let inverted = [at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)];
            std::iter::once(upright).chain((a + b + 1 < k).then_some(inverted))
        })
    })
}

/// The centroids of [`subdivision`]`(k)`'s parts, as barycentric coordinates: k² points spread evenly over
/// a triangle, each standing for an equal share of its area.
pub fn subdivision_centroids(k: usize) -> impl Iterator<Item = Vec2> {
    subdivision(k).map(|part| (part[0] + part[1] + part[2]) / 3.0)
}

/// The barycentric coordinates of `p` (on or near the triangle `v`'s plane), each clamped to the
/// triangle so that a point just off an edge takes the edge's.
pub fn barycentric(v: &[Vec3; 3], p: Vec3) -> [f32; 3] {
    let (e1, e2, d) = (v[1] - v[0], v[2] - v[0], p - v[0]);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let (b1, b2) = ((d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det);
    let b = [1.0 - b1 - b2, b1, b2].map(|x| x.max(0.0));
    let sum = b[0] + b[1] + b[2];
    b.map(|x| x / sum)
}

/// The area of triangle `v`.
pub fn triangle_area(v: &[Vec3; 3]) -> f32 {
    0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length()
}

/// Point `k` of `count` spread over triangles of `areas` (their sum `total` > 0), stratified by area: the
/// triangle holding the (k + ½)/count quantile of the area, and where in it, barycentric `(u, v)` of an R2
/// point folded into the triangle. Deterministic; the lights' hint points and the radiance cache's spread
/// points.
pub fn stratified_point(areas: &[f32], total: f32, k: usize, count: usize) -> (usize, f32, f32) {
    let mut target = (k as f32 + 0.5) / count as f32 * total;
    let i = areas.iter().position(|&a| {
        target -= a;
        target <= 0.0
    });
    let (mut u, mut v) = ((0.5 + 0.754_877_7 * k as f32).fract(), (0.5 + 0.569_840_3 * k as f32).fract());
    if u + v > 1.0 {
        (u, v) = (1.0 - u, 1.0 - v);
    }
    (i.unwrap_or(areas.len() - 1), u, v)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// k × k congruent parts, counter-clockwise as the triangle is, that tile it: their areas sum to its
    /// area and their centroids are distinct.
    #[test]
    fn a_subdivision_tiles_the_triangle() {
        for k in [1, 2, 3, 6] {
            let parts: Vec<[Vec2; 3]> = subdivision(k).collect();
            assert_eq!(parts.len(), k * k);
            let area = |p: &[Vec2; 3]| 0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0]);
            for p in &parts {
                assert!((area(p) - 0.5 / (k * k) as f32).abs() < 1e-6, "k {k}: {p:?} is not k² times smaller");
                assert!(p.iter().all(|b| b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6), "{p:?} outside");
            }
            let mut centroids: Vec<(i32, i32)> =
                parts.iter().map(|p| ((p[0] + p[1] + p[2]) * 1000.0 / 3.0).round().as_ivec2().into()).collect();
            centroids.sort_unstable();
            centroids.dedup();
            assert_eq!(centroids.len(), k * k, "k {k}: parts overlap");
        }
        let v = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert_eq!(at_barycentric(&v, Vec2::new(0.25, 0.5)), Vec3::new(0.25, 0.5, 0.0));
    }
}
