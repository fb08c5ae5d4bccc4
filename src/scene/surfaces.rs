//! Surface ids: within each group (one material), triangles that share an edge and bend by less than
//! [`CREASE_DEG`] belong to one surface. A box becomes six surfaces, a finely tessellated sphere one; the
//! refinement (which also compares normals) and the id-constrained filter then treat each as one piece.
//! Ids are numbered in the order of each surface's first triangle in the file, so they are stable.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use super::material::{Group, Material};
use super::{Surface, SurfaceId, Triangle};

/// Largest angle between the normals of two edge-sharing triangles of one surface.
pub const CREASE_DEG: f32 = 30.0;

/// What [`assign`] found besides the surfaces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dropped {
    /// Triangles without area, dropped.
    pub degenerate: usize,
    /// Triangles whose area (or edge lengths squared) overflows f32, with the first one and its group.
    pub overflowing: usize,
    pub first_overflowing: Option<(String, [Vec3; 3])>,
    /// Triangles with a corner that is not a finite number (NaN, infinite), with the first one and its group.
    pub not_finite: usize,
    pub first_not_finite: Option<(String, [Vec3; 3])>,
}

/// What [`assign`] makes of the groups.
pub struct Assigned {
    /// The triangles with area, with their surface ids.
    pub triangles: Vec<Triangle>,
    /// Their corners' shading normals ([`shading`]); empty where no group has any.
    pub normals: Vec<[Vec3; 3]>,
    /// Their corners' texture coordinates (0 in a group without); empty where no group has any.
    pub uvs: Vec<[Vec2; 3]>,
    /// Their corners' lightmap coordinates (NaN in a group without); empty where no group has any.
    pub lightmap_uvs: Vec<[Vec2; 3]>,
    pub surfaces: Vec<Surface>,
    /// What was left out.
    pub dropped: Dropped,
}

pub fn assign(groups: &[Group], materials: &[Material]) -> Assigned {
    let mut triangles = Vec::with_capacity(groups.iter().map(|g| g.triangles.len()).sum());
    let smooth = groups.iter().any(|g| !g.normals.is_empty());
    let mut normals = Vec::with_capacity(if smooth { triangles.capacity() } else { 0 });
    let textured = groups.iter().any(|g| !g.uvs.is_empty());
    let mut uvs = Vec::with_capacity(if textured { triangles.capacity() } else { 0 });
    let lightmapped = groups.iter().any(|g| !g.lightmap_uvs.is_empty());
    let mut lightmap_uvs = Vec::with_capacity(if lightmapped { triangles.capacity() } else { 0 });
    let mut surfaces = Vec::new();
    let mut dropped = Dropped::default();
    let cos_crease = CREASE_DEG.to_radians().cos();

    for group in groups {
        let mut local: Vec<([Vec3; 3], Vec3)> = Vec::with_capacity(group.triangles.len());
        for (k, &v) in group.triangles.iter().enumerate() {
            match face_normal(v) {
                Shape::Normal(n) => {
                    local.push((v, n));
                    if smooth {
                        normals.push(shading(group.normals.get(k), n));
                    }
                    if textured {
                        uvs.push(group.uvs.get(k).copied().unwrap_or([Vec2::ZERO; 3]));
                    }
                    if lightmapped {
                        lightmap_uvs.push(group.lightmap_uvs.get(k).copied().unwrap_or([Vec2::NAN; 3]));
                    }
                }
                Shape::Degenerate => dropped.degenerate += 1,
                Shape::Overflow => {
                    dropped.overflowing += 1;
                    dropped.first_overflowing.get_or_insert_with(|| (group.name.clone(), v));
                }
                Shape::NotFinite => {
                    dropped.not_finite += 1;
                    dropped.first_not_finite.get_or_insert_with(|| (group.name.clone(), v));
                }
            }
        }
        let mut sets = DisjointSets::new(local.len());
        // Edges as pairs of welded vertex ids, sorted so that the triangles sharing one are adjacent: flat
        // arrays, no allocation per edge (a 2M-triangle mesh has 3M edges).
        let corners = weld(local.iter().map(|(v, _)| v));
        let mut edges: Vec<(u64, u32)> = Vec::with_capacity(3 * local.len());
        for (i, c) in corners.chunks_exact(3).enumerate() {
            for k in 0..3 {
                let (a, b) = (c[k], c[(k + 1) % 3]);
                edges.push(((a.min(b) as u64) << 32 | a.max(b) as u64, i as u32));
            }
        }
        drop(corners);
        edges.sort_unstable();
        for run in edges.chunk_by(|a, b| a.0 == b.0) {
            for (k, &(_, i)) in run.iter().enumerate() {
                for &(_, j) in &run[..k] {
                    let (i, j) = (i as usize, j as usize);
                    if local[i].1.dot(local[j].1) >= cos_crease {
                        sets.union(i, j);
                    }
                }
            }
        }
        drop(edges);
        // Number this group's surfaces by first appearance (0: root not numbered yet).
        let mut ids: Vec<SurfaceId> = vec![0; local.len()];
        let first = surfaces.len();
        for (i, &(v, normal)) in local.iter().enumerate() {
            let root = sets.find(i);
            if ids[root] == 0 {
                surfaces.push(Surface { name: String::new(), material: group.material });
                ids[root] = surfaces.len() as SurfaceId;
            }
            let surface = ids[root];
            triangles.push(Triangle { v, normal, surface });
        }
        let count = surfaces.len() - first;
        let material = &materials[group.material].name;
        for (k, surface) in surfaces[first..].iter_mut().enumerate() {
            surface.name = if count == 1 {
                format!("{}/{material}", group.name)
            } else {
                format!("{}/{material}#{k}", group.name)
            };
        }
    }
    Assigned { triangles, normals, uvs, lightmap_uvs, surfaces, dropped }
}

/// A triangle's corners' shading normals from the file's (`given`, if any) and its front normal `face`: each
/// unit length and on the front's side (negated where the file's points behind it: the G-buffer turns the
/// normal towards the camera by the front side); the front normal where none is given or one is not a
/// direction.
pub fn shading(given: Option<&[Vec3; 3]>, face: Vec3) -> [Vec3; 3] {
    let Some(given) = given else { return [face; 3] };
    given.map(|n| match n.try_normalize() {
        Some(n) if n.dot(face) < 0.0 => -n,
        Some(n) => n,
        None => face,
    })
}

/// A triangle's shape as f32 arithmetic sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// The unit front normal (CCW winding).
    Normal(Vec3),
    /// No area.
    Degenerate,
    /// Finite corners, but twice its area or an edge length squared is beyond f32 (edges ≳ 1.8e19).
    Overflow,
    /// A corner is NaN or infinite.
    NotFinite,
}

pub fn face_normal(v: [Vec3; 3]) -> Shape {
    if !v.iter().all(|p| p.is_finite()) {
        return Shape::NotFinite;
    }
    let cross = (v[1] - v[0]).cross(v[2] - v[0]);
    let longest =
        (v[1] - v[0]).length_squared().max((v[2] - v[1]).length_squared()).max((v[0] - v[2]).length_squared());
    let area = cross.length();
    if !area.is_finite() || !longest.is_finite() {
        return Shape::Overflow;
    }
    // Relative test: area must not vanish against the triangle's own size. `normalize` (a multiply by the
    // reciprocal, not a division) keeps normals, and so every sensor frame, bit for bit what they were.
    if area > 1e-7 * longest { Shape::Normal(cross.normalize()) } else { Shape::Degenerate }
}

/// Welded vertex ids of the corners of `triangles` (three per triangle, in order): equal positions (bit for
/// bit, +0 and −0 alike) get one id, numbered by first appearance.
pub fn weld<'a>(triangles: impl Iterator<Item = &'a [Vec3; 3]>) -> Vec<u32> {
    let mut ids: HashMap<[u32; 3], u32, FxBuild> = HashMap::default();
    let mut corners = Vec::with_capacity(triangles.size_hint().0 * 3);
    for v in triangles {
        for p in v {
            let next = ids.len() as u32;
            corners.push(*ids.entry(bits(*p)).or_insert(next));
        }
    }
    corners
}

/// A fast, non-cryptographic hash (rustc's Fx) for position keys: SipHash took a fifth of a 2M-triangle load.
#[derive(Default)]
pub struct FxHasher(u64);

impl std::hash::Hasher for FxHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }
    fn write_u32(&mut self, x: u32) {
        self.write_u64(x as u64);
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

pub type FxBuild = std::hash::BuildHasherDefault<FxHasher>;

fn bits(p: Vec3) -> [u32; 3] {
    // +0.0 and −0.0 are the same point.
    [(p.x + 0.0).to_bits(), (p.y + 0.0).to_bits(), (p.z + 0.0).to_bits()]
}

struct DisjointSets {
    parent: Vec<usize>,
}

impl DisjointSets {
    fn new(n: usize) -> Self {
        Self { parent: (0..n).collect() }
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            // Keep the earlier triangle as root so numbering by first appearance is independent of union order.
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(corners: [Vec3; 4]) -> Vec<[Vec3; 3]> {
        vec![[corners[0], corners[1], corners[2]], [corners[0], corners[2], corners[3]]]
    }

    #[test]
    fn box_faces_are_separate_surfaces_and_quads_are_one() {
        let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
        let o = Vec3::ZERO;
        let mut triangles = quad([o, x, x + z, z]); // floor, y = 0
        triangles.extend(quad([o, y, y + x, x])); // wall z = 0, shares edge o–x at 90°
        let groups = [Group {
            name: "box".into(),
            material: 0,
            triangles,
            normals: Vec::new(),
            uvs: Vec::new(),
            lightmap_uvs: Vec::new(),
        }];
        let materials = [Material::new("m", Vec3::ONE, Vec3::ZERO)];
        let Assigned { triangles: tris, surfaces, dropped, .. } = assign(&groups, &materials);
        assert_eq!(dropped, Dropped::default());
        assert_eq!(surfaces.len(), 2);
        let ids: Vec<_> = tris.iter().map(|t| t.surface).collect();
        assert_eq!(ids, [1, 1, 2, 2]);
        assert_eq!(surfaces[0].name, "box/m#0");
    }

    /// The file's normals are made unit and turned to the front's side; one that is not a direction (zero)
    /// and a triangle without any take the front normal.
    #[test]
    fn shading_normals_are_unit_and_on_the_front() {
        let given = [Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.6, -0.8), Vec3::ZERO];
        assert_eq!(shading(Some(&given), Vec3::Z), [Vec3::Z, Vec3::new(0.0, -0.6, 0.8), Vec3::Z]);
        assert_eq!(shading(None, Vec3::X), [Vec3::X; 3]);
        // Through `assign`: only where some group gives normals, and one per kept triangle.
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let materials = [Material::new("m", Vec3::ONE, Vec3::ZERO)];
        let flat = [Group {
            name: "f".into(),
            material: 0,
            triangles: vec![[a, b, c]],
            normals: Vec::new(),
            uvs: Vec::new(),
            lightmap_uvs: Vec::new(),
        }];
        assert!(assign(&flat, &materials).normals.is_empty());
        let smooth = [
            Group {
                name: "s".into(),
                material: 0,
                triangles: vec![[a, b, b], [a, b, c]],
                normals: vec![[c; 3], given],
                uvs: Vec::new(),
                lightmap_uvs: Vec::new(),
            },
            flat[0].clone(),
        ];
        let Assigned { triangles, normals, .. } = assign(&smooth, &materials);
        assert_eq!(triangles.len(), 2, "the degenerate one dropped");
        assert_eq!(normals, [[Vec3::Z, Vec3::new(0.0, -0.6, 0.8), Vec3::Z], [Vec3::Z; 3]]);
    }

    #[test]
    fn weld_gives_equal_positions_one_id_and_signed_zeros_too() {
        let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0));
        let tris = [[a, b, c], [c, b, d], [Vec3::new(-0.0, 0.0, 0.0), d, b]];
        assert_eq!(weld(tris.iter()), [0, 1, 2, 2, 1, 3, 0, 3, 1]);
    }

    #[test]
    fn three_triangles_on_one_edge_join_only_the_flat_pairs() {
        // A fin: two coplanar triangles and a third at 90°, all on the edge o–x.
        let (o, x) = (Vec3::ZERO, Vec3::X);
        let triangles = vec![[o, x, Vec3::Z], [x, o, -Vec3::Z], [o, x, Vec3::Y]];
        let groups = [Group {
            name: "fin".into(),
            material: 0,
            triangles,
            normals: Vec::new(),
            uvs: Vec::new(),
            lightmap_uvs: Vec::new(),
        }];
        let materials = [Material::new("m", Vec3::ONE, Vec3::ZERO)];
        let Assigned { triangles: tris, surfaces, .. } = assign(&groups, &materials);
        assert_eq!(surfaces.len(), 2);
        assert_eq!(tris.iter().map(|t| t.surface).collect::<Vec<_>>(), [1, 1, 2]);
    }

    #[test]
    fn degenerate_triangles_are_dropped() {
        let groups = [Group {
            name: "g".into(),
            material: 0,
            triangles: vec![[Vec3::ZERO, Vec3::X, Vec3::X * 2.0], [Vec3::ZERO, Vec3::X, Vec3::Y]],
            normals: Vec::new(),
            uvs: Vec::new(),
            lightmap_uvs: Vec::new(),
        }];
        let materials = [Material::new("m", Vec3::ONE, Vec3::ZERO)];
        let Assigned { triangles: tris, surfaces, dropped, .. } = assign(&groups, &materials);
        assert_eq!((tris.len(), surfaces.len(), dropped.degenerate), (1, 1, 1));
        assert!((tris[0].normal - Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn an_area_beyond_f32_is_not_called_degenerate() {
        let big = [Vec3::ZERO, Vec3::X * 1e30, Vec3::Y * 1e30];
        assert_eq!(face_normal(big), Shape::Overflow);
        // Tiny but well-formed triangles keep their normal.
        assert_eq!(face_normal([Vec3::ZERO, Vec3::X * 1e-5, Vec3::Y * 1e-5]), Shape::Normal(Vec3::Z));
        assert_eq!(face_normal([Vec3::ZERO, Vec3::X, Vec3::X * 2.0]), Shape::Degenerate);
    }
}
