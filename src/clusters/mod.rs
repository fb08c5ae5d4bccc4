//! Clusters of triangles and their LOD hierarchy (docs/DESIGN.md §9), CPU only: a sensor needs geometry only
//! as fine as its texels, so a large mesh is split into clusters of at most [`MAX_TRIANGLES`] triangles and
//! simplified group by group, in the manner of Nanite and meshoptimizer's `clusterlod` ([`build`]).
//!
//! Every cluster carries two error bounds (a box and an object-space error): `own`, the bound of the
//! geometry it replaced (error 0 for the mesh's own triangles), and `parent`, the bound of what replaces it
//! (`f32::MAX` when nothing does). Both are bounds of whole groups, shared by every cluster that refers to
//! them and monotonic up the hierarchy (a group's box holds its children's, its error is at least
//! theirs), so that selecting, for one viewpoint,
//! `projected(own) <= τ < projected(parent)` ([`select`]) takes exactly one version of every piece of
//! surface and never cracks.
//!
//! Connected parts are simplified apart, each keeping every triangle's surface (a surface's vertices are its
//! own, so where surfaces meet they stay joined); a part of one cluster gets simpler levels of its own, and
//! emitters are never simplified: their clusters are full detail at every threshold ([`build`]). Built hierarchies are cached per mesh ([`cache`]). A bounding tree over the clusters
//! ([`tree`]) lets a viewpoint's selection skip whole regions and levels that it cannot take from.

pub mod build;
pub mod cache;
pub mod closed;
pub mod select;
pub mod tree;
mod weld;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::scene::Aabb;

pub use build::{BUILD_VERSION, MAX_TRIANGLES, build};
pub use select::{max_selected, projected_error, selected};
pub use tree::{CullTree, TreeNode};

/// The object-space error of a version of a piece of surface, and a box holding everything that version
/// stands for: its own triangles and, down the hierarchy, all those it replaced. Boxes, not
/// meshoptimizer's merged spheres: a group's footprint is the union of its children's, which a box holds
/// exactly, where spheres of spheres grew to three times the mesh within ten levels (and a sensor inside a
/// group's bound can take nothing coarser, so coarse levels went unused near the mesh).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ErrorBounds {
    pub min: [f32; 3],
    pub max: [f32; 3],
    /// Largest distance between this version of the surface and the original, in scene units; `f32::MAX`
    /// for "never good enough" (nothing replaces a terminal cluster).
    pub error: f32,
}

impl ErrorBounds {
    pub const FULL_DETAIL: f32 = 0.0;
    pub const TERMINAL: f32 = f32::MAX;

    pub fn new(bounds: Aabb, error: f32) -> Self {
        ErrorBounds { min: bounds.min.to_array(), max: bounds.max.to_array(), error }
    }

    /// Its box.
    pub fn aabb(&self) -> Aabb {
        Aabb { min: Vec3::from(self.min), max: Vec3::from(self.max) }
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
    /// A slab holding its triangles: unit axis (xyz, their mean normal) and half thickness (w) about the
    /// sphere's centre; with the sphere, a bound on how far they reach along any direction ([`reach`]),
    /// tight for the near-flat clusters of a smooth surface.
    pub slab: [f32; 4],
    /// The bound of the geometry this cluster replaced (error 0: it is the original).
    pub own: ErrorBounds,
    /// The bound of the geometry that replaces it (error `f32::MAX`: nothing does).
    pub parent: ErrorBounds,
    /// 1 where an eye outside `part_min`..`part_max` sees none of its part's back faces: the part is closed
    /// and faces outwards, or closed parts cap its rims ([`closed::hiding_boxes`]). 0 otherwise.
    pub closed: u32,
    pub _pad: u32,
    /// The box of its whole part (every level) and of the parts capping it: inside, an eye may see the
    /// part's back faces.
    pub part_min: [f32; 3],
    pub part_max: [f32; 3],
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
        self.positions.len() * 12
            + self.vertex_surface.len() * 4
            + self.indices.len() * 4
            + self.clusters.len() * size_of::<Cluster>()
    }
}

/// The representative of `s` in the union-find forest `parent` (each set led by its smallest member), the
/// path halved on the way.
fn root(parent: &mut [u32], mut s: u32) -> u32 {
    while parent[s as usize] != s {
        parent[s as usize] = parent[parent[s as usize] as usize];
        s = parent[s as usize];
    }
    s
}

/// Joins the sets of `a` and `b` in the forest `parent`, the smaller root leading.
fn join(parent: &mut [u32], a: u32, b: u32) {
    let (a, b) = (root(parent, a), root(parent, b));
    if a != b {
        parent[a.max(b) as usize] = a.min(b);
    }
}

/// The largest `dir · p` over the points of a cluster with this `sphere` and `slab`, at most: `dir` a unit
/// vector. The points lie in the sphere and within the slab's half thickness of its mid-plane, so along the
/// axis they reach `|dir · axis| · h` and across it `|dir × axis| · r` beyond the centre.
pub fn reach(sphere: [f32; 4], slab: [f32; 4], dir: Vec3) -> f32 {
    let (centre, axis) = (Vec3::from_slice(&sphere[..3]), Vec3::from_slice(&slab[..3]));
    let along = dir.dot(axis);
    let across = (1.0 - along * along).max(0.0).sqrt();
    dir.dot(centre) + along.abs() * slab[3] + across * sphere[3]
}

/// The slab of `triangles` about `centre`: their area-weighted mean normal (any axis where their normals
/// cancel) and the largest distance of a corner from the plane through `centre` across it, a little larger
/// than exact so that it still holds them after rounding on the GPU.
pub fn slab(triangles: impl Iterator<Item = [Vec3; 3]> + Clone, centre: Vec3) -> [f32; 4] {
    let normal: Vec3 = triangles.clone().map(|[a, b, c]| (b - a).cross(c - a)).sum();
    let axis = normal.try_normalize().unwrap_or(Vec3::Z);
    let half = triangles.flatten().map(|p| axis.dot(p - centre).abs()).fold(0.0f32, f32::max);
    axis.extend(half * (1.0 + 1e-5) + 1e-6 * centre.abs().max_element()).to_array()
}

/// Bounding sphere of `points`: the centre of their box and the farthest point from it.
pub fn sphere(points: impl Iterator<Item = Vec3> + Clone) -> [f32; 4] {
    let center = Aabb::of(points.clone()).center();
    let radius = points.map(|p| p.distance(center)).fold(0.0f32, f32::max);
    center.extend(radius).to_array()
}
