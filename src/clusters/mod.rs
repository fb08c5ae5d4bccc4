//! Clusters of triangles and their LOD hierarchy (docs/DESIGN.md §9), CPU only: a sensor needs geometry only
//! as fine as its texels, so a large mesh is split into clusters of at most [`MAX_TRIANGLES`] triangles and
//! simplified group by group, in the manner of Nanite and meshoptimizer's `clusterlod` ([`build`]).
//!
//! Every cluster carries two error bounds (a sphere and an object-space error): `own`, the bound of the
//! geometry it replaced (error 0 for the mesh's own triangles), and `parent`, the bound of what replaces it
//! (`f32::MAX` when nothing does). Both are bounds of whole groups, shared by every cluster that refers to
//! them and monotonic up the hierarchy, so that selecting, for one viewpoint,
//! `projected(own) <= τ < projected(parent)` ([`select`]) takes exactly one version of every piece of
//! surface and never cracks.
//!
//! Surfaces are simplified apart (a cluster never mixes surface ids, and a surface's border is locked, so
//! surfaces still meet), and emitters are never simplified: their clusters are full detail at every
//! threshold. Built hierarchies are cached per mesh ([`cache`]). A bounding tree over the clusters
//! ([`tree`]) lets a viewpoint's selection skip whole regions and levels that it cannot take from.

pub mod build;
pub mod cache;
pub mod select;
pub mod tree;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

pub use build::{BUILD_VERSION, MAX_TRIANGLES, build};
pub use select::{max_selected, projected_error, selected};
pub use tree::{CullTree, TreeNode};

/// A bounding sphere and the object-space error of the geometry it bounds (meshoptimizer's `clodBounds`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ErrorBounds {
    pub center: [f32; 3],
    pub radius: f32,
    /// Largest distance between this version of the surface and the original, in scene units; `f32::MAX`
    /// for "never good enough" (nothing replaces a terminal cluster).
    pub error: f32,
}

impl ErrorBounds {
    pub const FULL_DETAIL: f32 = 0.0;
    pub const TERMINAL: f32 = f32::MAX;

    pub fn center(&self) -> Vec3 {
        Vec3::from(self.center)
    }
}

/// One cluster: a run of `index_count / 3` triangles of one surface in [`ClusterMesh::indices`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Cluster {
    pub first_index: u32,
    pub index_count: u32,
    pub surface: u32,
    /// Depth in the hierarchy: 0 for the mesh's own triangles.
    pub depth: u32,
    /// Bounding sphere of its own triangles (centre, radius), for culling.
    pub sphere: [f32; 4],
    /// The bound of the geometry this cluster replaced (error 0: it is the original).
    pub own: ErrorBounds,
    /// The bound of the geometry that replaces it (error `f32::MAX`: nothing does).
    pub parent: ErrorBounds,
    pub _pad: [u32; 2],
}

impl Cluster {
    pub fn triangles(&self) -> u32 {
        self.index_count / 3
    }

    pub fn is_full_detail(&self) -> bool {
        self.own.error == ErrorBounds::FULL_DETAIL
    }
}

/// A mesh as clusters at every level of detail. Vertices are welded within each surface (so that a surface
/// is one connected mesh to simplify) and never shared between surfaces; each vertex knows its surface.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClusterMesh {
    pub positions: Vec<[f32; 3]>,
    /// Surface id of each vertex.
    pub vertex_surface: Vec<u32>,
    pub indices: Vec<u32>,
    /// Surface by surface, and within one surface finest first.
    pub clusters: Vec<Cluster>,
}

impl ClusterMesh {
    /// The triangles of cluster `c`, as vertex ids.
    pub fn triangles_of(&self, c: &Cluster) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.indices[c.first_index as usize..(c.first_index + c.index_count) as usize]
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
    }

    /// Triangles of the mesh itself (the full-detail clusters).
    pub fn full_detail_triangles(&self) -> usize {
        self.clusters.iter().filter(|c| c.is_full_detail()).map(|c| c.triangles() as usize).sum()
    }

    /// Bytes held, for statistics.
    pub fn bytes(&self) -> usize {
        self.positions.len() * 12 + self.vertex_surface.len() * 4 + self.indices.len() * 4 + self.clusters.len() * 72
    }
}

/// Bounding sphere of `points`: the centre of their box and the farthest point from it.
pub fn sphere(points: impl Iterator<Item = Vec3> + Clone) -> [f32; 4] {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for p in points.clone() {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let center = (lo + hi) * 0.5;
    let radius = points.map(|p| p.distance(center)).fold(0.0f32, f32::max);
    center.extend(radius).to_array()
}
