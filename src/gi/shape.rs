//! Which surfaces are corrugations of a larger shape (docs/DESIGN.md §10): their pieces are neither split
//! nor halved, and their planes split no other piece.
//!
//! A surface ends at a 30° crease (`scene::surfaces`). A fluted column is two surfaces per flute, the two
//! flanks of its groove 80° apart, each a strip a few centimetres wide. The planes of a cell's other
//! flanks cut each flank's piece (a split is meant for a wall standing on a floor), and cut up to eight
//! ways the 40 000-triangle hall's columns held 20 000 of its 28 000 entries, each sensed, for no better
//! light. A flank must keep its own entry: its groove's other flank sees it from a few centimetres (one
//! value for a quarter of the column, flanks facing the lamps and away alike, put 8 % of the hall's pixels
//! 20 % off). What tells a corrugation is that its shape faces elsewhere than it does: each surface's
//! normal summed with its neighbours' of the same material ([`SMOOTHING`] times over) is the shape's; a
//! surface [`CORRUGATED_DEG`] or more away from it, and narrow (its area over its longest extent under
//! [`NARROW`] of a cell), is a corrugation. A flank turns to its column's outward direction and is a few
//! centimetres wide; a room's floor may turn towards the wall it meets, but it is as wide as the room.

use std::collections::HashMap;

use glam::Vec3;

use crate::scene::surfaces::{FxBuild, weld};
use crate::scene::{Aabb, Mesh, SurfaceId, Triangle};

/// Times each surface's normal is summed with its neighbours' for its shape's normal: twice, so that a
/// groove's two flanks and the grooves beside it balance.
const SMOOTHING: usize = 2;

/// A surface whose mean normal is at least this far from its shape's, and [`NARROW`], is a corrugation.
pub const CORRUGATED_DEG: f32 = 30.0;
/// Narrow: a surface's area over the diagonal of its box under this share of a cell.
pub const NARROW: f32 = 0.25;

/// For each surface id (index 0 unused), whether it is a corrugation of a larger shape, with cells `cell`
/// wide. `local`: the mesh's own triangles (`Mesh::local_triangles`).
pub fn corrugated(mesh: &Mesh, local: &[Triangle], cell: f32) -> Vec<bool> {
    let surfaces = mesh.surfaces.len();
    let mut own = vec![Vec3::ZERO; surfaces + 1];
    let mut area = vec![0.0f32; surfaces + 1];
    let mut bounds = vec![Aabb::EMPTY; surfaces + 1];
    for t in local {
        let a = 0.5 * (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).length();
        own[t.surface as usize] += t.normal * a;
        area[t.surface as usize] += a;
        t.v.iter().for_each(|&p| bounds[t.surface as usize].grow(p));
    }
    // Surfaces of one material that share an edge (welded positions).
    let material = |s: SurfaceId| mesh.surfaces[s as usize - 1].material;
    let corners = weld(local.iter().map(|t| &t.v));
    let mut edges: HashMap<(u32, u32), SurfaceId, FxBuild> = HashMap::default();
    let mut neighbours: Vec<Vec<SurfaceId>> = vec![Vec::new(); surfaces + 1];
    for (t, c) in local.iter().zip(corners.chunks_exact(3)) {
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            let s = *edges.entry((a.min(b), a.max(b))).or_insert(t.surface);
            if s != t.surface && material(s) == material(t.surface) {
                neighbours[s as usize].push(t.surface);
                neighbours[t.surface as usize].push(s);
            }
        }
    }
    for n in &mut neighbours {
        n.sort_unstable();
        n.dedup();
    }
    let mut shape = own.clone();
    for _ in 0..SMOOTHING {
        shape =
            (0..=surfaces).map(|s| shape[s] + neighbours[s].iter().map(|&t| shape[t as usize]).sum::<Vec3>()).collect();
    }
    let cos = CORRUGATED_DEG.to_radians().cos();
    (0..=surfaces)
        .map(|s| {
            let (n, m) = (own[s].normalize_or_zero(), shape[s].normalize_or_zero());
            let narrow = area[s] < NARROW * cell * bounds[s].diagonal();
            s > 0 && n != Vec3::ZERO && m != Vec3::ZERO && n.dot(m) < cos && narrow
        })
        .collect()
}
