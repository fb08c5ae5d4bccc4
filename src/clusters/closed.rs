//! Which parts hide their back faces from an eye outside them (docs/DESIGN.md §9, "Back faces of closed
//! parts"). A ray from outside a closed surface that reaches one of its back faces has crossed one of its
//! front faces first, so the triangle pass drops the back faces of such a part for a sensor outside its box
//! (`glsl/cull_triangles.comp`): half the triangles a sensor drew in the hall of columns and spheres were
//! back faces. A part is such where it is closed and faces outwards, or where it is open only along rims
//! that faces of closed parts cap (a column's shaft standing on its plinth, under its capital).

use std::collections::HashMap;

use glam::{DVec3, Vec3};

use super::{join, root};
use crate::scene::Aabb;
use crate::scene::surfaces::{FxBuild, weld};

/// One part as the test reads it: its triangles (counter-clockwise seen from their front), and whether any
/// of its surfaces is cut out (a hole shows its back faces).
pub struct PartShape {
    pub triangles: Vec<[Vec3; 3]>,
    pub cut: bool,
}

/// For each part, the box outside which none of its back faces can be seen, or `None` where some may be:
/// its own box where it is closed and faces out ([`Edges::closed_outward`]); where its only open edges
/// are rims that closed parts' faces cap ([`caps`]), the box of it and of those parts (from inside them
/// their caps' backs show). Regular simplification keeps a closed surface closed and leaves rims where they are
/// (its open borders are locked), so every level of detail of such a part hides its back faces too.
pub fn hiding_boxes(parts: &[PartShape]) -> Vec<Option<Aabb>> {
    let edges: Vec<Edges> = parts.iter().map(|p| Edges::of(&p.triangles)).collect();
    let boxes: Vec<Aabb> = parts.iter().map(|p| Aabb::of(p.triangles.iter().flatten().copied())).collect();
    let closed: Vec<bool> = (parts.iter().zip(&edges)).map(|(p, e)| !p.cut && e.closed_outward()).collect();
    (0..parts.len())
        .map(|i| {
            if closed[i] {
                return Some(boxes[i]);
            }
            if parts[i].cut {
                return None;
            }
            let cappers = caps(boxes[i], &edges[i], |q| closed[q], parts, &boxes)?;
            Some(cappers.into_iter().fold(boxes[i], |b, q| b.union(boxes[q])))
        })
        .collect()
}

/// A part's edges, its corners welded where their positions are equal (triangles with two equal corners
/// left out: they hide nothing and add no volume).
struct Edges {
    positions: Vec<Vec3>,
    /// Per undirected edge (lower id first): uses along lower → higher, and along higher → lower.
    uses: HashMap<(u32, u32), (u32, u32), FxBuild>,
    /// Six times the signed volume the triangles enclose (with the origin).
    volume: f64,
}

impl Edges {
    fn of(triangles: &[[Vec3; 3]]) -> Self {
        let corners = weld(triangles.iter());
        let mut positions = vec![Vec3::ZERO; corners.iter().max().map_or(0, |&m| m as usize + 1)];
        for (&id, &p) in corners.iter().zip(triangles.iter().flatten()) {
            positions[id as usize] = p;
        }
        let mut uses: HashMap<(u32, u32), (u32, u32), FxBuild> = HashMap::default();
        let mut volume = 0.0f64;
        for (t, c) in triangles.iter().zip(corners.chunks_exact(3)) {
            if c[0] == c[1] || c[1] == c[2] || c[2] == c[0] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (c[k], c[(k + 1) % 3]);
                let e = uses.entry((a.min(b), a.max(b))).or_default();
                if a < b { e.0 += 1 } else { e.1 += 1 }
            }
            let [p, q, r] = t.map(|v| v.as_dvec3());
            volume += p.dot(q.cross(r));
        }
        Self { positions, uses, volume }
    }

    /// Every edge used exactly twice, once in each direction, and a positive volume.
    fn closed_outward(&self) -> bool {
        !self.uses.is_empty() && self.uses.values().all(|&u| u == (1, 1)) && self.volume > 0.0
    }

    /// The edges used once, as the triangles run along them (`a → b`); `None` where an edge is used
    /// otherwise than once each way or once in all (not a surface with rims).
    fn rims(&self) -> Option<Vec<(u32, u32)>> {
        let mut rims = Vec::new();
        for (&(a, b), &u) in &self.uses {
            match u {
                (1, 1) => {}
                (1, 0) => rims.push((a, b)),
                (0, 1) => rims.push((b, a)),
                _ => return None,
            }
        }
        Some(rims)
    }
}

/// The closed parts whose faces cap every rim of an open part (its box `bounds`, its `edges`), or `None`. A rim
/// (a loop of edges used once) is capped where it lies in a plane, the part closed by a flat cap on each
/// rim faces outwards, and the faces of one closed part in that plane facing the other way (into the
/// capped part: the closed part lies beyond the cap) form a convex polygon holding the whole rim: then a
/// ray from outside into the part's inside crosses the part or enters the closed part first.
fn caps(
    bounds: Aabb,
    edges: &Edges,
    closed: impl Fn(usize) -> bool,
    parts: &[PartShape],
    boxes: &[Aabb],
) -> Option<Vec<usize>> {
    let rims = edges.rims()?;
    if rims.is_empty() {
        return None;
    }
    let scale = bounds.diagonal().max(f32::MIN_POSITIVE) as f64;
    let eps = 1e-5 * scale;
    let p = |v: u32| edges.positions[v as usize].as_dvec3();
    // The rims' loops: their edges grouped by shared corners.
    let mut parent: Vec<u32> = (0..edges.positions.len() as u32).collect();
    for &(a, b) in &rims {
        join(&mut parent, a, b);
    }
    let mut loops: HashMap<u32, Vec<(u32, u32)>, FxBuild> = HashMap::default();
    for &(a, b) in &rims {
        loops.entry(root(&mut parent, a)).or_default().push((a, b));
    }
    let mut volume = edges.volume;
    let mut cappers = Vec::new();
    for rim in loops.values() {
        let corners: Vec<DVec3> = rim.iter().map(|&(a, _)| p(a)).collect();
        let centre = corners.iter().sum::<DVec3>() / corners.len() as f64;
        // The cap closing the part: (centre, b, a) for each rim edge a → b; its normal points out of the
        // part's inside.
        let area: DVec3 = rim.iter().map(|&(a, b)| (p(b) - centre).cross(p(a) - centre)).sum();
        volume += rim.iter().map(|&(a, b)| centre.dot(p(b).cross(p(a)))).sum::<f64>();
        let n = area.try_normalize()?;
        if corners.iter().any(|c| (c - centre).dot(n).abs() > eps) {
            return None; // not flat
        }
        let capper = (0..parts.len()).find(|&q| {
            let b = boxes[q];
            closed(q)
                && corners
                    .iter()
                    .all(|c| c.cmpge(b.min.as_dvec3() - eps).all() && c.cmple(b.max.as_dvec3() + eps).all())
                && covers(&parts[q].triangles, (centre, n), &corners, eps)
        })?;
        cappers.push(capper);
    }
    // Outwards, and enclosing a volume (a flat sheet on a face and its cap enclose none).
    (volume > 1e-6 * scale.powi(3)).then_some(cappers)
}

/// Whether the faces among `triangles` that lie in the plane through `centre` with normal `n` and face
/// against `n` form one convex polygon holding every point of `corners` (within `eps`).
fn covers(triangles: &[[Vec3; 3]], (centre, n): (DVec3, DVec3), corners: &[DVec3], eps: f64) -> bool {
    let (u, v) = n.any_orthonormal_pair();
    let flat = |q: DVec3| glam::DVec2::new((q - centre).dot(u), (q - centre).dot(v));
    let mut points = Vec::new();
    let mut area = 0.0;
    for t in triangles {
        let [a, b, c] = t.map(|x| x.as_dvec3());
        let normal = (b - a).cross(c - a);
        if [a, b, c].iter().any(|x| (x - centre).dot(n).abs() > eps) || normal.dot(n) >= 0.0 {
            continue;
        }
        area += normal.length() / 2.0;
        points.extend([a, b, c].map(flat));
    }
    if points.is_empty() {
        return false;
    }
    let hull = convex_hull(points);
    let hull_area = (0..hull.len()).map(|i| hull[i].perp_dot(hull[(i + 1) % hull.len()])).sum::<f64>() / 2.0;
    // The faces tile their hull (no gap: a convex polygon) and the rim lies within it.
    let edge_eps = eps * (hull_area.abs().sqrt() + eps);
    (hull_area - area).abs() <= 1e-6 * hull_area.max(f64::MIN_POSITIVE)
        && corners
            .iter()
            .map(|&c| flat(c))
            .all(|c| (0..hull.len()).all(|i| (hull[(i + 1) % hull.len()] - hull[i]).perp_dot(c - hull[i]) >= -edge_eps))
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain).
fn convex_hull(mut points: Vec<glam::DVec2>) -> Vec<glam::DVec2> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let mut hull: Vec<glam::DVec2> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &glam::DVec2>> =
            if pass == 0 { Box::new(points.iter()) } else { Box::new(points.iter().rev()) };
        for &q in iter {
            while hull.len() >= start + 2
                && (hull[hull.len() - 1] - hull[hull.len() - 2]).perp_dot(q - hull[hull.len() - 2]) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box's twelve triangles, counter-clockwise seen from outside.
    fn cuboid(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
        let v = |i: usize| Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), hi, lo);
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        quads.iter().flat_map(|q| [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]]).collect()
    }

    /// An open square tube of half width `r` around the y axis from `y0` to `y1`, facing out: its rims are
    /// its ends.
    fn tube(r: f32, (y0, y1): (f32, f32)) -> Vec<[Vec3; 3]> {
        let corner = |k: usize, y: f32| {
            let (x, z) = [(r, r), (-r, r), (-r, -r), (r, -r)][k % 4];
            Vec3::new(x, y, z)
        };
        (0..4)
            .flat_map(|k| {
                let (a, b, c, d) = (corner(k, y0), corner(k + 1, y0), corner(k + 1, y1), corner(k, y1));
                [[a, d, c], [a, c, b]]
            })
            .collect()
    }

    fn closed_outward(triangles: &[[Vec3; 3]]) -> bool {
        Edges::of(triangles).closed_outward()
    }

    fn boxes(parts: Vec<Vec<[Vec3; 3]>>) -> Vec<Option<Aabb>> {
        hiding_boxes(&parts.into_iter().map(|triangles| PartShape { triangles, cut: false }).collect::<Vec<_>>())
    }

    #[test]
    fn a_cube_is_closed_facing_out_and_not_once_opened_or_turned_inside_out() {
        let cube = cuboid(Vec3::ZERO, Vec3::ONE);
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
        let cut = hiding_boxes(&[PartShape { triangles: cube, cut: true }]);
        assert_eq!(cut, vec![None], "a closed part with a cut-out shows its back faces through it");
    }

    /// A shaft on a plinth under a capital: its ends are capped by the boxes' faces, so from outside the
    /// three boxes none of its back faces shows. Not where an end is left open, the shaft is wider than the
    /// face its end stands on, or the shaft faces in.
    #[test]
    fn a_tube_capped_by_closed_parts_hides_its_back_faces() {
        let plinth = cuboid(Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 0.3, 0.5));
        let capital = cuboid(Vec3::new(-0.5, 5.0, -0.5), Vec3::new(0.5, 5.5, 0.5));
        let shaft = tube(0.35, (0.3, 5.0));
        let whole = Aabb { min: Vec3::new(-0.5, 0.0, -0.5), max: Vec3::new(0.5, 5.5, 0.5) };
        let hiding = boxes(vec![plinth.clone(), capital.clone(), shaft.clone()]);
        assert!(hiding[0].is_some() && hiding[1].is_some(), "the boxes are closed");
        assert_eq!(hiding[2], Some(whole), "the capped shaft, from outside it and its boxes");
        assert_eq!(boxes(vec![plinth.clone(), shaft.clone()])[1], None, "its top left open");
        let wide = tube(0.6, (0.3, 5.0));
        assert_eq!(boxes(vec![plinth.clone(), capital.clone(), wide])[2], None, "wider than the faces");
        let inward: Vec<[Vec3; 3]> = shaft.iter().map(|&[a, b, c]| [a, c, b]).collect();
        assert_eq!(boxes(vec![plinth.clone(), capital.clone(), inward])[2], None, "facing in");
        let short = tube(0.35, (0.3, 4.9));
        assert_eq!(boxes(vec![plinth, capital, short])[2], None, "its top short of the capital");
    }
}
