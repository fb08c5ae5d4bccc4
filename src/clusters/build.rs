//! Building the hierarchy with meshoptimizer's `clusterlod`: split a piece of the mesh into clusters,
//! partition them into groups, simplify each group with its border locked, split the result again, and
//! repeat until a level no longer simplifies. Regular (not sloppy, not permissive) simplification only, so
//! that a closed surface stays closed at every level: sloppy simplification where the regular one got
//! stuck opened the 40 000-triangle hall's walls at a distance, and its cache came out 1 % too dark.
//!
//! The pieces are the mesh's connected parts (surfaces that share an edge; emitters apart), not its
//! surfaces: a surface ends at a 30° crease, and a fluted column is two surfaces per flute, each a strip
//! whose locked border kept it at 130 triangles however far away it was seen (58 000 triangles a sensor in
//! a hall of columns). Within a part, each surface keeps its own vertices (welded within the surface), so
//! where two surfaces meet meshoptimizer sees a seam: it may shorten it, moving both sides' vertices
//! alike, but never opens it, and every triangle keeps the vertices, and so the surface, it had. A part of
//! one cluster, which `clusterlod` leaves as it is, gets simpler levels of its own (`Part::push_levels`).
//! A part as a whole vanishes where it projects under a view's accepted error (`Part::vanish_when_small`).

use glam::Vec3;
use meshopt::{ClodMesh, VertexDataAdapter, clod_build, clod_default_config, typed_to_bytes};
use rayon::prelude::*;

use super::{Cluster, ClusterMesh, ErrorBounds, slab, sphere};
use crate::scene::surfaces::{FxBuild, weld};
use crate::scene::{Aabb, Mesh, closest_on_triangle};

/// Bumped whenever the output of [`build`] changes: cached hierarchies of another version are rebuilt.
pub const BUILD_VERSION: u32 = 7;
/// Triangles per cluster at most (and vertices: meshoptimizer's default for rasterisation).
pub const MAX_TRIANGLES: usize = 128;
/// A small part's next level has at most this fraction of its previous level's triangles (1 / ratio).
const LEVEL_RATIO: usize = 4;

/// Clusters of one connected part of the mesh, indices local to its own vertices.
struct Part {
    /// Its first surface: what its clusters carry as [`Cluster::surface`].
    surface: u32,
    positions: Vec<[f32; 3]>,
    /// The surface of each of its vertices.
    vertex_surface: Vec<u32>,
    indices: Vec<u32>,
    clusters: Vec<Cluster>,
}

/// The cluster hierarchy of `mesh`: each connected part of it apart (every emitting surface alone), at full
/// detail only where it is an emitter or fits one cluster.
pub fn build(mesh: &Mesh) -> ClusterMesh {
    let mut by_surface: Vec<Vec<&[Vec3; 3]>> = vec![Vec::new(); mesh.surfaces.len() + 1];
    for t in &mesh.triangles {
        by_surface[t.surface as usize].push(&t.v);
    }
    let parts: Vec<Part> = connected_parts(mesh)
        .par_iter()
        .map(|surfaces| {
            let triangles: Vec<(&[Vec3; 3], u32)> =
                surfaces.iter().flat_map(|&s| by_surface[s as usize].iter().map(move |&v| (v, s))).collect();
            let emitter = mesh.material_of(surfaces[0]).is_emitter();
            let lod = match triangles.len() {
                _ if emitter => PartLod::FullOnly,
                n if n > MAX_TRIANGLES => PartLod::Hierarchy,
                _ => PartLod::Levels,
            };
            let mut part = part_clusters(&triangles, surfaces[0], lod);
            if !emitter {
                part.vanish_when_small();
            }
            part
        })
        .collect();
    let mut out = ClusterMesh::default();
    for part in parts {
        let (base_vertex, base_index) = (out.positions.len() as u32, out.indices.len() as u32);
        out.vertex_surface.extend(part.vertex_surface);
        out.positions.extend(part.positions);
        out.indices.extend(part.indices.iter().map(|&v| v + base_vertex));
        out.clusters
            .extend(part.clusters.into_iter().map(|c| Cluster { first_index: c.first_index + base_index, ..c }));
    }
    out
}

/// The mesh's surfaces in connected parts: surfaces that share an edge (welded positions) are one part,
/// but an emitting surface is a part of its own. Each part's surfaces increasing, parts by their first.
fn connected_parts(mesh: &Mesh) -> Vec<Vec<u32>> {
    let surfaces = mesh.surfaces.len();
    let mut parent: Vec<u32> = (0..=surfaces as u32).collect();
    fn root(parent: &mut [u32], mut s: u32) -> u32 {
        while parent[s as usize] != s {
            parent[s as usize] = parent[parent[s as usize] as usize];
            s = parent[s as usize];
        }
        s
    }
    let emitter = |s: u32| mesh.material_of(s).is_emitter();
    let corners = weld(mesh.triangles.iter().map(|t| &t.v));
    let mut edges: std::collections::HashMap<(u32, u32), u32, FxBuild> = Default::default();
    for (t, c) in mesh.triangles.iter().zip(corners.chunks_exact(3)) {
        if emitter(t.surface) {
            continue;
        }
        for k in 0..3 {
            let edge = (c[k].min(c[(k + 1) % 3]), c[k].max(c[(k + 1) % 3]));
            let other = *edges.entry(edge).or_insert(t.surface);
            let (a, b) = (root(&mut parent, other), root(&mut parent, t.surface));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut parts: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for s in 1..=surfaces as u32 {
        let r = root(&mut parent, s);
        parts.entry(r).or_default().push(s);
    }
    parts.into_values().collect()
}

/// How a part is drawn from afar.
#[derive(Clone, Copy, PartialEq, Eq)]
enum PartLod {
    /// At full detail only (an emitter: its light is sensed as it is).
    FullOnly,
    /// As one cluster at successively simpler levels (a part of at most [`MAX_TRIANGLES`] triangles).
    Levels,
    /// Through meshoptimizer's cluster hierarchy.
    Hierarchy,
}

/// The clusters of one part's `triangles` (each with its surface), carrying `surface`.
fn part_clusters(triangles: &[(&[Vec3; 3], u32)], surface: u32, lod: PartLod) -> Part {
    // Vertices welded within each surface, numbered part-wide.
    let mut ids: std::collections::HashMap<(u32, [u32; 3]), u32, FxBuild> = Default::default();
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut vertex_surface: Vec<u32> = Vec::new();
    let mut corners: Vec<u32> = Vec::with_capacity(3 * triangles.len());
    for &(v, s) in triangles {
        for p in v {
            let key = (s, p.to_array().map(|x| (x + 0.0).to_bits()));
            let id = *ids.entry(key).or_insert_with(|| {
                positions.push(p.to_array());
                vertex_surface.push(s);
                positions.len() as u32 - 1
            });
            corners.push(id);
        }
    }
    let mut part = Part { surface, positions, vertex_surface, indices: Vec::new(), clusters: Vec::new() };
    match lod {
        PartLod::FullOnly => {
            // Runs of the surface's triangles in file order.
            for run in corners.chunks(3 * MAX_TRIANGLES) {
                part.push(run, 0, ErrorBounds::default(), terminal());
            }
            return part;
        }
        PartLod::Levels => {
            part.push_levels(&corners);
            return part;
        }
        PartLod::Hierarchy => {}
    }
    let config = meshopt::ClodConfig {
        simplify_permissive: false,
        simplify_fallback_sloppy: false,
        ..clod_default_config(MAX_TRIANGLES)
    };
    let bytes = typed_to_bytes(&part.positions);
    let vertices = VertexDataAdapter::new(bytes, 12, 0).expect("positions are 12-byte vertices");
    // (group, refined group or -1, indices) per cluster; each group's simplified bounds.
    let mut groups: Vec<(u32, ErrorBounds)> = Vec::new();
    let mut clusters: Vec<(usize, i32, Vec<u32>)> = Vec::new();
    // Each group's box holds its members' triangles and the boxes of the groups they came from, which
    // come first (a group is emitted after the groups its members were simplified from).
    let positions = &part.positions;
    clod_build(config, &ClodMesh::new(&corners, &vertices), |group, emitted| {
        let id = groups.len();
        let mut footprint = Aabb::EMPTY;
        for c in emitted {
            footprint = footprint.union(Aabb::of(c.indices.iter().map(|&v| Vec3::from(positions[v as usize]))));
            if c.refined >= 0 {
                footprint = footprint.union(groups[c.refined as usize].1.aabb());
            }
        }
        groups.push((group.depth as u32, ErrorBounds::new(footprint, group.simplified.error)));
        clusters.extend(emitted.iter().map(|c| (id, c.refined, c.indices.to_vec())));
        id as i32
    });
    // Finest first, so that a surface's full-detail triangles are one run.
    clusters.sort_by_key(|&(group, refined, _)| (refined >= 0, group));
    for (group, refined, indices) in clusters {
        let (depth, parent) = groups[group];
        let parent = if parent.error >= f32::MAX { terminal() } else { parent };
        let own = if refined < 0 { ErrorBounds::default() } else { groups[refined as usize].1 };
        let depth = if refined < 0 { 0 } else { depth };
        part.push(&indices, depth, own, parent);
    }
    part
}

/// The directed Hausdorff distance from `from` to `to`, sampled: the largest distance from a corner, an
/// edge's middle or the centroid of a triangle of `from` to the nearest triangle of `to`. Quadratic: small
/// parts only.
fn hausdorff(from: &[[Vec3; 3]], to: &[[Vec3; 3]]) -> f32 {
    let samples =
        from.iter().flat_map(|&[a, b, c]| [a, b, c, (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0, (a + b + c) / 3.0]);
    samples
        .map(|p| to.iter().map(|&[a, b, c]| closest_on_triangle(p, a, b, c).distance(p)).fold(f32::MAX, f32::min))
        .fold(0.0, f32::max)
}

fn terminal() -> ErrorBounds {
    ErrorBounds { error: ErrorBounds::TERMINAL, ..Default::default() }
}

impl Part {
    /// What replaces the part's coarsest clusters, where nothing else does: nothing, at an error of half its
    /// box's diagonal (a shape shrunk to a point is that far from where it was). A part that projects under
    /// a view's accepted error as a whole (a vase across the atrium, a leaf, under a texel) is not drawn:
    /// the many small parts of a real model (Sponza: 41 000 triangles in parts of one cluster) would
    /// otherwise be drawn at full detail however far away.
    fn vanish_when_small(&mut self) {
        let part = Aabb::of(self.positions.iter().map(|&p| Vec3::from(p)));
        for c in self.clusters.iter_mut().filter(|c| c.parent.error == ErrorBounds::TERMINAL) {
            let error = (0.5 * part.diagonal()).max(c.own.error);
            c.parent = ErrorBounds::new(part.union(c.own.aabb()), error);
        }
    }

    /// A small part (one cluster) as a chain of levels, each from simplifying the full detail to a quarter
    /// of the previous level's triangles, until a level no longer simplifies by a quarter. Without them, a
    /// small part is drawn at full detail until it vanishes: Sponza's 656 leaves (45 triangles each) and
    /// its other parts of one cluster were a quarter of the triangles its sensors drew. Regular
    /// simplification, so a closed part stays closed; each level's error is measured against the full
    /// detail, made monotonic, and its box is the part's.
    fn push_levels(&mut self, corners: &[u32]) {
        let bytes = typed_to_bytes(&self.positions);
        let vertices = VertexDataAdapter::new(bytes, 12, 0).expect("positions are 12-byte vertices");
        let options = meshopt::SimplifyOptions::ErrorAbsolute;
        let full = self.corners(corners);
        let mut levels: Vec<(Vec<u32>, f32)> = vec![(corners.to_vec(), ErrorBounds::FULL_DETAIL)];
        loop {
            let (previous, previous_error) = levels.last().expect("the full detail");
            let target = previous.len() / 3 / LEVEL_RATIO;
            if target < 1 {
                break;
            }
            let mut estimate = 0.0;
            let simpler = meshopt::simplify(corners, &vertices, 3 * target, f32::MAX, options, Some(&mut estimate));
            if simpler.is_empty() || simpler.len() * 4 > previous.len() * 3 {
                break;
            }
            // meshoptimizer's estimate, or the distance measured between the two surfaces where larger (on a
            // small ball, the mesh's vertices lay 1.4 times the estimate from the simpler level); never 0 (a
            // level coarser than the mesh is never full detail) and never below the last.
            let level = self.corners(&simpler);
            let measured = hausdorff(&full, &level).max(hausdorff(&level, &full));
            let error = estimate.max(measured).max(*previous_error).max(f32::MIN_POSITIVE);
            levels.push((simpler, error));
        }
        let part = Aabb::of(self.positions.iter().map(|&p| Vec3::from(p)));
        let bounds = |level: Option<&(Vec<u32>, f32)>| match level {
            Some(&(_, error)) if error == ErrorBounds::FULL_DETAIL => ErrorBounds::default(),
            Some(&(_, error)) => ErrorBounds::new(part, error),
            None => terminal(),
        };
        for (depth, (indices, _)) in levels.iter().enumerate() {
            let own = bounds(levels.get(depth));
            let parent = bounds(levels.get(depth + 1));
            self.push(indices, depth as u32, own, parent);
        }
    }

    /// The triangles of `indices` by their corners.
    fn corners(&self, indices: &[u32]) -> Vec<[Vec3; 3]> {
        indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| Vec3::from(self.positions[t[k] as usize]))).collect()
    }

    fn push(&mut self, indices: &[u32], depth: u32, own: ErrorBounds, parent: ErrorBounds) {
        let positions = &self.positions;
        let points = indices.iter().map(|&v| Vec3::from(positions[v as usize]));
        let sphere = sphere(points);
        let corners = indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| Vec3::from(positions[t[k] as usize])));
        self.clusters.push(Cluster {
            first_index: self.indices.len() as u32,
            index_count: indices.len() as u32,
            surface: self.surface,
            depth,
            sphere,
            slab: slab(corners, Vec3::from_slice(&sphere[..3])),
            own,
            parent,
            _pad: [0; 2],
        });
        self.indices.extend_from_slice(indices);
    }
}
