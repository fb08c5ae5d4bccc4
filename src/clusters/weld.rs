//! Welding a part's corners across surfaces that look alike, for simplifying (docs/DESIGN.md §9): where two
//! such surfaces meet meshoptimizer sees no seam, so a column's flutes fold into a plain shaft at coarser
//! levels, where seams kept each groove's two flanks apart at every level. The full detail keeps every
//! triangle's own surface; a coarser triangle is turned to start at the corner whose surface faces as it
//! does ([`Welded::unweld`]).

use glam::Vec3;

use crate::scene::surfaces::FxBuild;

/// Surfaces that look alike are welded where their normals are less than this far apart (radians): a
/// column's flanks meet at 117° at its ridges. Welded at any angle (a blade's two faces too), Crytek
/// Sponza's sensors read R 1.3 % off the full detail's, three times as far as with no welding.
const WELD_ANGLE: f32 = 0.75 * std::f32::consts::PI;

/// What a surface looks like to a sensor, apart from its shape: its material and its albedo's texture mean
/// (bits). Surfaces that look alike are welded for simplifying.
pub type Look = (usize, [u32; 3]);

/// One triangle of a part: its corners, surface, and texture coordinates where the mesh has them.
pub type PartTriangle<'a> = (&'a [Vec3; 3], u32, Option<&'a [glam::Vec2; 3]>);

/// The part's corners welded across surfaces that look alike, for simplifying: `corners` index `positions`;
/// each of them stands for the part's vertices `sides[i]` welded there (the first its first), each with its
/// surface's normal at it (area-weighted, unit).
pub struct Welded {
    pub positions: Vec<[f32; 3]>,
    pub sides: Vec<Vec<(u32, Vec3)>>,
    pub corners: Vec<u32>,
}

impl Welded {
    /// `triangles`' corners (`part_corners`: the part's own vertex of each) welded by `look` (of a surface),
    /// position and texture coordinates, where their surfaces' normals there are less than [`WELD_ANGLE`]
    /// apart.
    pub fn new(
        triangles: &[PartTriangle],
        part_corners: &[u32],
        positions: &[[f32; 3]],
        look: impl Fn(u32) -> Look,
    ) -> Self {
        let mut normals = vec![Vec3::ZERO; positions.len()];
        for (&(v, _, _), own) in triangles.iter().zip(part_corners.chunks_exact(3)) {
            let normal = (v[1] - v[0]).cross(v[2] - v[0]);
            own.iter().for_each(|&o| normals[o as usize] += normal);
        }
        normals.iter_mut().for_each(|n| *n = n.normalize_or_zero());
        // By (look, position bits, texture coordinate bits): the welded ids there, each facing its own way.
        type Key = (Look, [u32; 3], [u32; 2]);
        let mut ids: std::collections::HashMap<Key, Vec<u32>, FxBuild> = Default::default();
        let mut welded_as = vec![u32::MAX; positions.len()];
        let mut out = Welded { positions: Vec::new(), sides: Vec::new(), corners: Vec::new() };
        for (&(v, s, uvs), own) in triangles.iter().zip(part_corners.chunks_exact(3)) {
            for k in 0..3 {
                let o = own[k] as usize;
                if welded_as[o] == u32::MAX {
                    let uv = uvs.map_or([0; 2], |uv| uv[k].to_array().map(|x| (x + 0.0).to_bits()));
                    let key = (look(s), v[k].to_array().map(|x| (x + 0.0).to_bits()), uv);
                    let candidates = ids.entry(key).or_default();
                    let close = |&&w: &&u32| out.sides[w as usize][0].1.dot(normals[o]) >= WELD_ANGLE.cos();
                    welded_as[o] = match candidates.iter().find(close) {
                        Some(&w) => w,
                        None => {
                            out.positions.push(positions[o]);
                            out.sides.push(Vec::new());
                            candidates.push(out.sides.len() as u32 - 1);
                            out.sides.len() as u32 - 1
                        }
                    };
                    out.sides[welded_as[o] as usize].push((own[k], normals[o]));
                }
                out.corners.push(welded_as[o]);
            }
        }
        out
    }

    /// Simplified `indices` (welded ids) as the part's own vertices. A triangle takes the surface of its
    /// first corner (the provoking vertex), so each is turned (its winding kept) to start at the corner
    /// whose surface faces most as it does: a column's flutes simplified into one facet read the flank
    /// that faces like the facet (each corner stands for its own vertex of that surface). Against its
    /// oracle the hall's image came out 1.2 % dark with the first corner's first surface, 0.6 % with this.
    pub fn unweld(&self, indices: &[u32]) -> Vec<u32> {
        let mut out = Vec::with_capacity(indices.len());
        for t in indices.chunks_exact(3) {
            let p = |k: usize| Vec3::from(self.positions[t[k] as usize]);
            let normal = (p(1) - p(0)).cross(p(2) - p(0));
            let facing = |k: usize| self.sides[t[k] as usize].iter().map(move |&(own, n)| (k, own, n.dot(normal)));
            let (first, own, _) = (0..3)
                .flat_map(facing)
                .fold((0, self.sides[t[0] as usize][0].0, f32::MIN), |best, c| if c.2 > best.2 { c } else { best });
            out.push(own);
            out.extend([1, 2].map(|k| self.sides[t[(first + k) % 3] as usize][0].0));
        }
        out
    }

    /// The full detail's `indices` (welded ids, triangles in any order and rotation) as the part's own
    /// triangles, each with the surface it had: the corners `part_corners` that weld to the same triangle.
    pub fn full_detail(&self, part_corners: &[u32]) -> impl FnMut(&[u32]) -> Vec<u32> {
        let rotated = |t: [u32; 3], by: usize| [t[by], t[(by + 1) % 3], t[(by + 2) % 3]];
        let lowest = |t: [u32; 3]| (0..3).min_by_key(|&k| t[k]).expect("three corners");
        let mut own: std::collections::HashMap<[u32; 3], Vec<[u32; 3]>, FxBuild> = Default::default();
        for (w, p) in self.corners.chunks_exact(3).zip(part_corners.chunks_exact(3)) {
            let (w, p) = ([w[0], w[1], w[2]], [p[0], p[1], p[2]]);
            let by = lowest(w);
            own.entry(rotated(w, by)).or_default().push(rotated(p, by));
        }
        move |indices| {
            let mut out = Vec::with_capacity(indices.len());
            for t in indices.chunks_exact(3) {
                let t = [t[0], t[1], t[2]];
                let by = lowest(t);
                let p = own.get_mut(&rotated(t, by)).and_then(Vec::pop).expect("a full-detail triangle of the part");
                out.extend_from_slice(&rotated(p, (3 - by) % 3));
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles of one look sharing the edge from (0, 0, 0) to (0, 0, 1), the second folded about it
    /// by `angle` (radians, between their normals): the welded corners.
    fn welded_corners(angle: f32) -> Vec<u32> {
        let a = [Vec3::ZERO, Vec3::Z, Vec3::X];
        let b = [Vec3::Z, Vec3::ZERO, Vec3::new(-angle.cos(), angle.sin(), 0.0)];
        let triangles: Vec<PartTriangle> = vec![(&a, 1, None), (&b, 2, None)];
        let positions: Vec<[f32; 3]> = a.iter().chain(&b).map(|p| p.to_array()).collect();
        Welded::new(&triangles, &[0, 1, 2, 3, 4, 5], &positions, |_| (0, [0; 3])).corners
    }

    #[test]
    fn surfaces_of_one_look_weld_unless_they_face_apart() {
        // A column's flanks at a ridge, 117° apart: the shared edge's corners weld.
        assert_eq!(welded_corners(117f32.to_radians()), [0, 1, 2, 1, 0, 3]);
        // A fold sharper than WELD_ANGLE (a blade's two faces): each keeps its own corners.
        assert_eq!(welded_corners(160f32.to_radians()), [0, 1, 2, 3, 4, 5]);
    }
}
