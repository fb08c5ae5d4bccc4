//! A glTF file's materials: base colour and emission, their textures (from a buffer view, a file or a
//! `data:` URI, each image read once), cut-outs, and what of a material is not used, said once per
//! material a primitive uses.

use anyhow::{Context as _, Result};
use glam::Vec3;

use super::Reader;
use crate::scene::material::{Cutout, Material, MaterialFormat};
use crate::scene::texture::Texture;

impl Reader<'_> {
    /// One material per glTF material, in order, then the default (white) at the end.
    pub(super) fn materials(&mut self, document: &gltf::Document) -> Result<()> {
        for m in document.materials() {
            let name = m.name().map_or_else(|| format!("material#{}", m.index().unwrap_or(0)), str::to_owned);
            let pbr = m.pbr_metallic_roughness();
            let [r, g, b, alpha] = pbr.base_color_factor();
            let ke = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
            let mut unused = Vec::new();
            let kd_map = self.texture(&name, "base colour", pbr.base_color_texture(), &mut unused)?;
            let ke_map = self.texture(&name, "emissive", m.emissive_texture(), &mut unused)?;
            let index = self.mesh.materials.len();
            if ke_map.is_some() && ke.max_element() <= 0.0 {
                let note =
                    format!("material '{name}': its emissive texture is multiplied by factor 0: it emits nothing");
                self.material_notes.push((index, note));
            }
            if pbr.metallic_factor() > 0.0 {
                unused.push("metalness (treated as diffuse)".into());
            }
            if m.alpha_mode() == gltf::material::AlphaMode::Blend {
                unused.push("alpha blending (drawn opaque)".into());
            }
            // MASK with a texture: cut out where factor × texture alpha < cutoff (a factor under the cutoff
            // cuts the whole primitive out, in `mesh_at`).
            let mut cutout = match (m.alpha_mode(), kd_map) {
                (gltf::material::AlphaMode::Mask, Some(map)) if alpha > 0.0 => {
                    Some(Cutout { map, threshold: m.alpha_cutoff().unwrap_or(0.5) / alpha })
                }
                _ => None,
            };
            if cutout.is_some() && ke.max_element() > 0.0 {
                unused.push("alpha mask (an emitter is not cut out)".into());
                cutout = None;
            }
            if !unused.is_empty() {
                self.material_notes.push((index, format!("material '{name}': {} not used", unused.join(", "))));
            }
            self.mesh.materials.push(Material {
                kd_map,
                ke_map,
                cutout,
                format: MaterialFormat::Gltf,
                ..Material::new(&name, Vec3::new(r, g, b), ke)
            });
        }
        let default = Material::new("(glTF default, white)", Vec3::ONE, Vec3::ZERO);
        self.mesh.materials.push(Material { format: MaterialFormat::Gltf, ..default });
        self.used_materials = vec![false; self.mesh.materials.len()];
        Ok(())
    }

    /// Material `material`'s `what` texture `info` (base colour, emissive): its image where it is placed by
    /// TEXCOORD_0; on a later set it is not used, said in `unused`.
    pub(super) fn texture(
        &mut self,
        material: &str,
        what: &str,
        info: Option<gltf::texture::Info>,
        unused: &mut Vec<String>,
    ) -> Result<Option<usize>> {
        match info {
            Some(info) if info.tex_coord() != 0 => {
                unused.push(format!("its {what} texture (on TEXCOORD_1 or later; the factor is used)"));
                Ok(None)
            }
            Some(info) => self.image(material, what, info.texture().source()),
            None => Ok(None),
        }
    }

    /// The texture of `image`, read once (from a buffer view, a file or a `data:` URI) for material
    /// `material`'s `what` ("base colour", "emissive"; both are sRGB): a file that cannot be read is a warning
    /// (the factor alone is used), an image that cannot be decoded an error naming it.
    pub(super) fn image(&mut self, material: &str, what: &str, image: gltf::Image) -> Result<Option<usize>> {
        if let Some(&(_, texture)) = self.images.iter().find(|(i, _)| *i == image.index()) {
            return Ok(texture);
        }
        let label = image.name().map_or_else(|| format!("image#{}", image.index()), str::to_owned);
        let bytes = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()].0;
                let range = view.offset()..view.offset() + view.length();
                let bytes = buffer.get(range).with_context(|| {
                    format!("{}: image {label}: its buffer view runs past its buffer", self.path.display())
                })?;
                Some(bytes.to_vec())
            }
            gltf::image::Source::Uri { uri, .. } => {
                match gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), Some(self.base)) {
                    Ok(data) => Some(data.0),
                    Err(e) => {
                        let shown = if uri.starts_with("data:") { "(a data: URI)" } else { uri };
                        self.warn(format!(
                            "material '{material}': cannot read its {what} texture {shown}: {e}; the factor alone \
                             is used"
                        ));
                        None
                    }
                }
            }
        };
        let texture = match bytes {
            Some(bytes) => {
                let texture = Texture::decode(&bytes, &format!("{label} of {}", self.path.display()))
                    .with_context(|| format!("{}: material '{material}'", self.path.display()))?;
                self.mesh.textures.push(texture);
                Some(self.mesh.textures.len() - 1)
            }
            None => None,
        };
        self.images.push((image.index(), texture));
        Ok(texture)
    }

    /// Material `index`, or where it has a texture and the primitive `name` no texture coordinates, its copy
    /// without the texture (said).
    pub(super) fn material_without_coordinates(&mut self, index: usize, name: &str) -> usize {
        if !self.mesh.materials[index].is_textured() {
            return index;
        }
        if let Some(&(_, copy)) = self.untextured.iter().find(|(m, _)| *m == index) {
            return copy;
        }
        let material = self.mesh.materials[index].untextured();
        self.warn(format!(
            "{name}: material '{}' has a texture but the primitive no TEXCOORD_0; the factors alone are used, not \
             cut out",
            material.name
        ));
        self.mesh.materials.push(material);
        let copy = self.mesh.materials.len() - 1;
        self.untextured.push((index, copy));
        copy
    }
}
