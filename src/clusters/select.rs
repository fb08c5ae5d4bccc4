//! Level-of-detail selection for one viewpoint: the rule the GPU culling pass applies per sensor view, and
//! its CPU twin.

use glam::Vec3;

use super::{Cluster, ErrorBounds};

/// The angle (radians, small-angle) that `bounds`' error subtends at best from `eye`: its error over the
/// distance from `eye` to its box (at least `near`). Rotation invariant, so it needs no view direction;
/// the same bounds give the same value for every cluster that shares them, and a bound that holds another
/// with no smaller error never gives less.
pub fn projected_error(bounds: &ErrorBounds, eye: Vec3, near: f32) -> f32 {
    if bounds.error == ErrorBounds::FULL_DETAIL {
        return 0.0;
    }
    bounds.error / bounds.aabb().distance(eye).max(near)
}

/// Whether `cluster` is the version of its piece of surface to draw from `eye` when an error of `tau`
/// radians is acceptable: its own error is, and its parent's is not.
pub fn selected(cluster: &Cluster, eye: Vec3, near: f32, tau: f32) -> bool {
    projected_error(&cluster.own, eye, near) <= tau && projected_error(&cluster.parent, eye, near) > tau
}

/// An upper bound on the clusters any selection of `mesh` takes, from any viewpoint at any `tau`: what
/// the culling pass must leave room for per view so that no view loses geometry.
///
/// A selection is the finest level with some groups replaced by what simplifying them produced (in an order
/// that respects the hierarchy), so it holds at most the full-detail clusters plus, over the groups, every
/// excess of a group's replacement over its members. A group is keyed by its bounds (and surface): its
/// members' `parent` and its replacement's `own` are the same bounds.
pub fn max_selected(mesh: &super::ClusterMesh) -> usize {
    use std::collections::HashMap;
    let key =
        |surface: u32, b: &ErrorBounds| (surface, b.min.map(f32::to_bits), b.max.map(f32::to_bits), b.error.to_bits());
    let mut balance: HashMap<_, i64> = HashMap::new();
    let mut full = 0usize;
    for c in &mesh.clusters {
        if c.is_full_detail() {
            full += 1;
        } else {
            *balance.entry(key(c.surface, &c.own)).or_default() += 1;
        }
        if c.parent.error != ErrorBounds::TERMINAL {
            *balance.entry(key(c.surface, &c.parent)).or_default() -= 1;
        }
    }
    full + balance.values().map(|&b| b.max(0) as usize).sum::<usize>()
}
