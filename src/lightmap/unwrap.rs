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
    /// Where the coordinates came from.
    pub source: Source,
}

/// Where a lightmap's coordinates came from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// The file's own (glTF `TEXCOORD_1`).
    File,
    /// Made by `uvunwrap`; `Some(why)` where the file's were refused.
    Unwrapped(Option<String>),
}

/// Where the surface folds by more than this at a hard edge (its sides' shading normals differ), a chart
/// ends. The renderer shows such an edge as a jump in the light (a box's edge; each facet of a flat-shaded
/// pillar takes its own normal's light), and a chart unfolded across it would blend the two sides in every
/// bilinear fetch along it: a Cornell box's short block at a 256² atlas had pixels along its front's edge
/// 150 % too bright, the room's 16-sided pillar (22.5° a facet) stripes of ±20 %. Finer facets stay in
/// one chart: cut at every facet (1°), the 40 000-triangle hall's fluted columns made 10 505 charts on 3
/// pages, at 20° 1 382 on one, and the room is 0.97 % off `render` either way. Edges whose shading normals
/// are shared (a smooth mesh) stay inside charts: their light is continuous.
pub const CREASE_DEGREES: f32 = 20.0;

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

/// The lightmap's coordinates of `mesh`'s local triangles (not the sun's disc) at `density`, in pages of at
/// most `max_side` texels a side (the device's largest image): the file's own where every triangle has
/// them, inside the page and overlapping nowhere; else made by [`make`] (saying why the file's were not
/// taken).
pub fn unwrap(mesh: &Mesh, density: Density, max_side: u32) -> Result<Unwrapped> {
    let local = mesh.local_triangles().len();
    if mesh.lightmap_uvs.len() < local {
        return make(mesh, density, max_side, None);
    }
    match from_file(mesh, density, max_side)? {
        Ok(unwrapped) => Ok(unwrapped),
        Err(why) => make(mesh, density, max_side, Some(why)),
    }
}

/// The file's `TEXCOORD_1` as the lightmap's coordinates, or why they cannot serve: a primitive without
/// them, coordinates outside [0, 1], or two triangles on one texel centre (a lightmap shared by two
/// points is wrong at one of them).
fn from_file(mesh: &Mesh, density: Density, max_side: u32) -> Result<std::result::Result<Unwrapped, String>> {
    let local = mesh.local_triangles();
    let uv = &mesh.lightmap_uvs[..local.len()];
    if let Some(t) = uv.iter().position(|c| c.iter().any(|p| !p.is_finite())) {
        return Ok(Err(format!("triangle {t} has no TEXCOORD_1 (not every primitive has them)")));
    }
    if let Some(t) = uv.iter().position(|c| c.iter().any(|p| p.min_element() < -1e-4 || p.max_element() > 1.0 + 1e-4)) {
        return Ok(Err(format!("TEXCOORD_1 of triangle {t} leaves [0, 1] ({:?})", uv[t])));
    }
    // Surface area, and the page's share the coordinates cover: the density they give a side of texels.
    let area = surface_area(local);
    let uv_area: f64 = uv.iter().map(|c| ((c[1] - c[0]).perp_dot(c[2] - c[0]) / 2.0).abs() as f64).sum();
    let side = match density {
        Density::Side(side) => side,
        // The side at which the texels average `d` per unit of area.
        Density::PerUnit(d) => (d as f64 * (area / uv_area.max(1e-12)).sqrt()).ceil() as u32,
    };
    ensure!(
        (1..=max_side).contains(&side),
        "the lightmap of TEXCOORD_1 at this density would be {side} texels a side, beyond this device's largest \
         image ({max_side}); give a smaller --texels-per-unit or --size"
    );
    if let Some((texel, a, b)) = overlap(uv, side) {
        return Ok(Err(format!(
            "TEXCOORD_1 overlaps itself: triangles {a} and {b} both cover texel ({}, {}) of {side} × {side}",
            texel % side,
            texel / side
        )));
    }
    Ok(Ok(Unwrapped {
        uv: uv.to_vec(),
        page: vec![0; uv.len()],
        width: side,
        height: side,
        pages: 1,
        texels_per_unit: (side as f64 * (uv_area / area.max(1e-30)).sqrt()) as f32,
        charts: 0,
        source: Source::File,
    }))
}

/// The triangles' area, summed in f64.
fn surface_area(triangles: &[crate::scene::Triangle]) -> f64 {
    triangles.iter().map(|t| crate::scene::triangle_area(&t.v) as f64).sum()
}

/// The first texel centre of a `side`² page that two triangles of `uv` cover (strictly inside both), with
/// the two.
pub fn overlap(uv: &[[Vec2; 3]], side: u32) -> Option<(u32, usize, usize)> {
    let mut owner = vec![u32::MAX; side as usize * side as usize];
    let scale = Vec2::splat(side as f32);
    for (t, c) in uv.iter().enumerate() {
        let c = c.map(|p| p * scale);
        let area = (c[1] - c[0]).perp_dot(c[2] - c[0]);
        if area.abs() < 1e-12 {
            continue;
        }
        let (lo, hi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
        for y in (lo.y.floor().max(0.0) as u32)..(hi.y.ceil() as u32).min(side) {
            for x in (lo.x.floor().max(0.0) as u32)..(hi.x.ceil() as u32).min(side) {
                let q = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                // Strictly inside, by a margin: a centre on an edge two triangles of a chart share is no overlap.
                let inside =
                    (0..3).all(|k| (c[(k + 1) % 3] - c[k]).perp_dot(q - c[k]) * area.signum() > 1e-4 * area.abs());
                if inside {
                    let i = (y * side + x) as usize;
                    if owner[i] != u32::MAX {
                        return Some((i as u32, owner[i] as usize, t));
                    }
                    owner[i] = t as u32;
                }
            }
        }
    }
    None
}

/// Unwraps `mesh`'s local triangles with `uvunwrap` at `density` (see [`unwrap`]); `why`: why the file's
/// coordinates were not taken. A density whose atlas could not fit is refused before unwrapping, with what
/// it would need. Charts never span two materials.
fn make(mesh: &Mesh, density: Density, max_side: u32, why: Option<String>) -> Result<Unwrapped> {
    let triangles = mesh.local_triangles();
    if let Density::PerUnit(d) = density {
        let area = surface_area(triangles);
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
        source: Source::Unwrapped(why),
    })
}
