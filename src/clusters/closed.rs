//! Which parts are closed and face outwards: their back faces are hidden from any eye outside them
//! (docs/DESIGN.md §9, "Back faces of closed parts"). A ray from outside that reaches a back face of such
//! a surface has crossed a front face of it first, so the triangle pass drops the back faces of a closed
//! part for a sensor outside its box (`glsl/cull_triangles.comp`): half the triangles a sensor drew in the
//! hall of columns and spheres were back faces.

use std::collections::HashMap;

use glam::Vec3;

use crate::scene::surfaces::FxBuild;

/// Whether `triangles` (counter-clockwise seen from their front) close a volume and face out of it: every
/// edge (corners welded where their positions are equal) is used exactly twice, once in each direction,
/// and the signed volume they enclose is positive. Triangles with two equal corners are left out (they
/// hide nothing and add no volume). Regular simplification keeps a closed surface closed, so every level
/// of detail of such a part is closed too (docs/DESIGN.md §9).
pub fn closed_outward<'a>(triangles: impl IntoIterator<Item = &'a [Vec3; 3]>) -> bool {
    let mut ids: HashMap<[u32; 3], u32, FxBuild> = HashMap::default();
    let mut id = |p: Vec3| {
        let next = ids.len() as u32;
        *ids.entry(p.to_array().map(f32::to_bits)).or_insert(next)
    };
    // Per undirected edge (lower id first): uses along lower → higher, and along higher → lower.
    let mut edges: HashMap<(u32, u32), (u32, u32), FxBuild> = HashMap::default();
    let mut volume = 0.0f64;
    for t in triangles {
        let c = t.map(&mut id);
        if c[0] == c[1] || c[1] == c[2] || c[2] == c[0] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            let uses = edges.entry((a.min(b), a.max(b))).or_default();
            if a < b {
                uses.0 += 1;
            } else {
                uses.1 += 1;
            }
        }
        let [p, q, r] = t.map(|v| v.as_dvec3());
        volume += p.dot(q.cross(r));
    }
    !edges.is_empty() && edges.values().all(|&uses| uses == (1, 1)) && volume > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's twelve triangles, counter-clockwise seen from outside.
    fn cube() -> Vec<[Vec3; 3]> {
        let v = |i: usize| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        quads.iter().flat_map(|q| [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]]).collect()
    }

    #[test]
    fn a_cube_is_closed_facing_out_and_not_once_opened_or_turned_inside_out() {
        let cube = cube();
        assert!(closed_outward(&cube));
        assert!(!closed_outward(&cube[1..]), "a face opened");
        let inside_out: Vec<[Vec3; 3]> = cube.iter().map(|&[a, b, c]| [a, c, b]).collect();
        assert!(!closed_outward(&inside_out), "a room seen from inside");
        let mut flipped = cube.clone();
        flipped[0] = [flipped[0][0], flipped[0][2], flipped[0][1]];
        assert!(!closed_outward(&flipped), "one triangle turned");
        let mut twice = cube.clone();
        twice.extend(cube.iter().map(|&[a, b, c]| [a, b, c].map(|p| p + Vec3::X * 2.0)));
        assert!(closed_outward(&twice), "two cubes apart, each closed");
        let mut touching = cube.clone();
        touching.extend(cube.iter().map(|&[a, b, c]| [a, b, c].map(|p| p + Vec3::X)));
        assert!(!closed_outward(&touching), "two cubes sharing a face: its edges used four times");
    }
}
