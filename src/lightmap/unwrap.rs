//! The lightmap's texture coordinates (glTF's `TEXCOORD_1`): a second UV set in which no two triangles
//! share a texel, made by `uvunwrap` (charts grown over nearly flat regions, flattened by LSCM, packed with a
//! gutter so that bilinear filtering and mipmaps do not bleed one chart into another).

use std::collections::HashMap;

use anyhow::{Result, bail, ensure};
use glam::{Vec2, Vec3};

use crate::scene::Mesh;

/// How dense the atlas is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Density {
    /// The highest density at which every chart fits one page of this side, in texels (typical 256–2048).
    Side(u32),
    /// This many texels per scene unit; the page grows to fit (typical: 8–64 per metre for a room).
    PerUnit(f32),
}

/// Empty texels around each chart: charts lie at least twice this apart. Two covers bilinear filtering and
/// the first mip level.
pub const GUTTER: u32 = 2;

/// The unwrapped mesh: each local triangle's corners in the atlas, and the atlas's size.
#[derive(Clone, Debug)]
pub struct Unwrapped {
    /// Per triangle of [`Mesh::local_triangles`], its corners' coordinates in `[0, 1]` of its page ((0, 0):
    /// the top-left corner of texel row 0, column 0, as glTF's texture coordinates).
    pub uv: Vec<[Vec2; 3]>,
    /// Each triangle's page (0 where it got no texels).
    pub page: Vec<u32>,
    pub width: u32,
    pub height: u32,
    pub pages: u32,
    pub texels_per_unit: f32,
    pub charts: u32,
}

/// Where the surface folds by more than this at a hard edge (its sides' shading normals differ), a chart
/// ends. The renderer shows such an edge as a jump in the light (a box's edge; each facet of a flat-shaded
/// pillar takes its own normal's light), and a chart unfolded across it would blend the two sides in every
/// bilinear fetch along it: a Cornell box's short block at a 256² atlas had pixels along its front's edge
/// 150 % too bright, the room's 16-sided pillar stripes of ±20 %. Edges whose shading normals are shared
/// (a smooth mesh) stay inside charts: their light is continuous.
pub const CREASE_DEGREES: f32 = 1.0;

/// Each local triangle's edges (corner k to k + 1) that are chart boundaries: folds by more than
/// [`CREASE_DEGREES`] whose two sides do not share their shading normals (an edge no other triangle
/// shares in the opposite direction is one anyway).
fn creases(mesh: &Mesh) -> Vec<[bool; 3]> {
    let triangles = mesh.local_triangles();
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut edges: HashMap<([u32; 3], [u32; 3]), (usize, usize)> = HashMap::with_capacity(3 * triangles.len());
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            edges.insert((key(tri.v[k]), key(tri.v[(k + 1) % 3])), (t, k));
        }
    }
    let normal = |t: usize, k: usize| mesh.shading.get(t).map_or(triangles[t].normal, |n| n[k % 3]);
    let cos = CREASE_DEGREES.to_radians().cos();
    (triangles.iter().enumerate())
        .map(|(t, tri)| {
            [0, 1, 2].map(|k| match edges.get(&(key(tri.v[(k + 1) % 3]), key(tri.v[k]))) {
                Some(&(u, j)) => {
                    // Triangle u runs the edge from its corner j (our k + 1) to j + 1 (our k).
                    let smooth =
                        normal(t, k).dot(normal(u, j + 1)) > 0.999 && normal(t, k + 1).dot(normal(u, j)) > 0.999;
                    tri.normal.dot(triangles[u].normal) < cos && !smooth
                }
                None => false,
            })
        })
        .collect()
}

/// Unwraps `mesh`'s local triangles (not the sun's disc) at `density`, into pages of at most `max_side`
/// texels a side (the device's largest image). Charts never span two materials. A density whose atlas
/// could not fit is refused before unwrapping, with what it would need.
pub fn unwrap(mesh: &Mesh, density: Density, max_side: u32) -> Result<Unwrapped> {
    let triangles = mesh.local_triangles();
    if let Density::PerUnit(d) = density {
        let area: f64 = triangles.iter().map(|t| crate::scene::triangle_area(&t.v) as f64).sum();
        let longest = (triangles.iter())
            .flat_map(|t| [(0, 1), (1, 2), (2, 0)].map(|(i, j)| t.v[i].distance(t.v[j])))
            .fold(0.0f32, f32::max);
        let (texels, side) = (area * (d as f64).powi(2), longest * d);
        let most = (max_side as f64).powi(2);
        if texels > most || side > max_side as f32 {
            bail!(
                "at {d} texels per unit the lightmap needs at least {texels:.3e} texels (its longest edge {side:.0} \
                 texels), beyond this device's largest image ({max_side} a side, {most:.3e} texels); give a smaller \
                 --texels-per-unit or --size"
            );
        }
    }
    if let Density::Side(side) = density {
        ensure!(side <= max_side, "--size {side} is beyond this device's largest image ({max_side} a side)");
    }
    let positions: Vec<[f32; 3]> = triangles.iter().flat_map(|t| t.v.map(|p| p.to_array())).collect();
    let indices: Vec<u32> = (0..positions.len() as u32).collect();
    let materials: Vec<u32> = triangles.iter().map(|t| mesh.surfaces[t.surface as usize - 1].material as u32).collect();
    let seams = creases(mesh);
    let input = uvunwrap::MeshInput {
        face_materials: Some(&materials),
        seams: Some(&seams),
        ..uvunwrap::MeshInput::new(&positions, &indices)
    };
    let density = match density {
        Density::Side(side) => uvunwrap::Density::Auto { page_size: side },
        Density::PerUnit(texels_per_unit) => uvunwrap::Density::Fixed { texels_per_unit, page_size: None },
    };
    let options = uvunwrap::Options { density, padding: GUTTER, ..uvunwrap::Options::default() };
    let atlas = match uvunwrap::generate(&[input], &options) {
        Ok(atlas) => atlas,
        Err(e) => bail!("cannot unwrap the mesh for its lightmap: {e}"),
    };
    let out = &atlas.meshes[0];
    let corner = |k: usize| out.vertices[out.indices[k] as usize];
    let uv = (0..triangles.len()).map(|t| [0, 1, 2].map(|k| Vec2::from(corner(3 * t + k).uv))).collect();
    let page = (0..triangles.len()).map(|t| (0..3).find_map(|k| corner(3 * t + k).page).unwrap_or(0)).collect();
    Ok(Unwrapped {
        uv,
        page,
        width: atlas.width,
        height: atlas.height,
        pages: atlas.page_count.max(1),
        texels_per_unit: atlas.texels_per_unit,
        charts: atlas.chart_count,
    })
}
