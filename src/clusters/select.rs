//! Level-of-detail selection for one viewpoint: the rule the GPU culling pass applies per sensor view, and
//! its CPU twin.

use glam::Vec3;

use super::{Cluster, ErrorBounds};

/// The angle (radians, small-angle) that `bounds`' error subtends at best from `eye`: its error over the
/// nearest distance from `eye` to its sphere (at least `near`). Rotation invariant, so it needs no view
/// direction; the same bounds give the same value for every cluster that shares them.
pub fn projected_error(bounds: &ErrorBounds, eye: Vec3, near: f32) -> f32 {
    if bounds.error == ErrorBounds::FULL_DETAIL {
        return 0.0;
    }
    let distance = (bounds.center().distance(eye) - bounds.radius).max(near);
    bounds.error / distance
}

/// Whether `cluster` is the version of its piece of surface to draw from `eye` when an error of `tau`
/// radians is acceptable: its own error is, and its parent's is not.
pub fn selected(cluster: &Cluster, eye: Vec3, near: f32, tau: f32) -> bool {
    projected_error(&cluster.own, eye, near) <= tau && projected_error(&cluster.parent, eye, near) > tau
}
