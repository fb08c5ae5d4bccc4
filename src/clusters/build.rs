//! Building the hierarchy with meshoptimizer's `clusterlod`: split a surface into clusters, partition them
//! into groups, simplify each group with its border locked, split the result again, and repeat until a
//! level no longer simplifies. Regular (not sloppy, not permissive) simplification only, so that a closed
//! surface stays closed at every level.

use glam::Vec3;
use meshopt::{ClodMesh, VertexDataAdapter, clod_build, clod_default_config, typed_to_bytes};
use rayon::prelude::*;

use super::{Cluster, ClusterMesh, ErrorBounds, slab, sphere};
use crate::scene::surfaces::weld;
use crate::scene::{Aabb, Mesh};

/// Bumped whenever the output of [`build`] changes: cached hierarchies of another version are rebuilt.
pub const BUILD_VERSION: u32 = 3;
/// Triangles per cluster at most (and vertices: meshoptimizer's default for rasterisation).
pub const MAX_TRIANGLES: usize = 128;

/// Clusters of one surface, indices local to its own vertices.
struct Part {
    surface: u32,
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    clusters: Vec<Cluster>,
}

/// The cluster hierarchy of `mesh`: every surface apart, emitters at full detail only.
pub fn build(mesh: &Mesh) -> ClusterMesh {
    let mut by_surface: Vec<Vec<[Vec3; 3]>> = vec![Vec::new(); mesh.surfaces.len()];
    for t in &mesh.triangles {
        by_surface[t.surface as usize - 1].push(t.v);
    }
    let parts: Vec<Part> = by_surface
        .par_iter()
        .enumerate()
        .map(|(i, triangles)| {
            let surface = i as u32 + 1;
            let simplify = !mesh.material_of(surface).is_emitter() && triangles.len() > MAX_TRIANGLES;
            surface_clusters(triangles, surface, simplify)
        })
        .collect();
    let mut out = ClusterMesh::default();
    for (i, part) in parts.into_iter().enumerate() {
        let (base_vertex, base_index) = (out.positions.len() as u32, out.indices.len() as u32);
        out.vertex_surface.extend(std::iter::repeat_n(i as u32 + 1, part.positions.len()));
        out.positions.extend(part.positions);
        out.indices.extend(part.indices.iter().map(|&v| v + base_vertex));
        out.clusters
            .extend(part.clusters.into_iter().map(|c| Cluster { first_index: c.first_index + base_index, ..c }));
    }
    out
}

fn surface_clusters(triangles: &[[Vec3; 3]], surface: u32, simplify: bool) -> Part {
    let corners = weld(triangles.iter());
    let mut positions = vec![[0.0f32; 3]; corners.iter().max().map_or(0, |&m| m as usize + 1)];
    for (t, c) in triangles.iter().zip(corners.chunks_exact(3)) {
        for k in 0..3 {
            positions[c[k] as usize] = t[k].to_array();
        }
    }
    let mut part = Part { surface, positions, indices: Vec::new(), clusters: Vec::new() };
    if !simplify {
        // Full detail only: runs of the surface's triangles in file order.
        for run in corners.chunks(3 * MAX_TRIANGLES) {
            part.push(run, 0, ErrorBounds::default(), terminal());
        }
        return part;
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

fn terminal() -> ErrorBounds {
    ErrorBounds { error: ErrorBounds::TERMINAL, ..Default::default() }
}

impl Part {
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
