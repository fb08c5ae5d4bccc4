//! The mesh a scene renders: its triangles with their surfaces, shading normals, texture coordinates,
//! materials and textures, built from what a loader read; what it says of its light; its emitters split
//! by their textures; the sun's disc.

use anyhow::{Result, bail, ensure};
use glam::{Vec2, Vec3};

use super::geometry::{Aabb, SurfaceId, Triangle, at_barycentric, interpolate, subdivision, triangle_area};
use super::material::{Group, Material};
use super::texture::Texture;
use super::{Sun, surfaces};

/// Most parts of all emission-textured triangles together ([`Mesh::emitter_split`]): each part is an emitter
/// that every sensor's exact emitter term sums.
pub const MAX_TEXTURED_EMITTER_PARTS: usize = 4096;

/// Most parts a side of one emission-textured triangle is cut into ([`Mesh::emitter_parts`]): 8 × 8 parts
/// measured within 0.4 % of the oracle on a 4 × 4-texel panel.
pub const MAX_EMITTER_SPLIT: usize = 8;

/// A surface: the triangles of one group and material that form one connected, nearly flat patch. The
/// refinement and the filter never mix two surfaces (paper §III-G, §III-H).
#[derive(Clone, Debug)]
pub struct Surface {
    /// "group/material", for messages and AOV legends.
    pub name: String,
    pub material: usize,
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
    /// Each triangle's corners' lightmap coordinates from the file (glTF's `TEXCOORD_1`; NaN where its
    /// primitive has none); empty where none has any. `sensorlight bake` lays its lightmap by them.
    pub lightmap_uvs: Vec<[Vec2; 3]>,
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
        groups: &[Group],
        materials: Vec<Material>,
        textures: Vec<Texture>,
        warnings: &mut Vec<String>,
    ) -> Result<Self> {
        let surfaces::Assigned { triangles, normals: shading, uvs, lightmap_uvs, surfaces, dropped } =
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
        let mut mesh = Self {
            triangles,
            shading,
            uvs,
            lightmap_uvs,
            surfaces,
            materials,
            textures,
            texture_mean: Vec::new(),
            bounds,
        };
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
    pub(super) fn remove_sun(&mut self) {
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
