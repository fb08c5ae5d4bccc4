//! Triangle culling (docs/DESIGN.md §9): after the culling pass has chosen each view's clusters, drop the
//! triangles of those clusters that cannot cover a texel of the view, so that the maps draw about what
//! their texels see rather than whole clusters. Shader: `glsl/cull_triangles.comp`. CPU twin: [`may_cover`].
//!
//! A cluster kept for a view near the sensor is kept whole, but most of its triangles may lie outside the
//! view or fall between its texel centres: a fluted column's flank is one long cluster, drawn at full
//! detail for a sensor at its foot, whose far end covers a few texels with hundreds of triangles. On a
//! CPU rasterizer every triangle costs vertex shading, clipping and setup on one thread; a compute pass
//! tests them on every core.
//!
//! The culling pass's walk appends each command it writes to a list; this pass takes one such cluster per
//! invocation, tests its triangles in turn and appends the survivors' indices to its view's region of
//! the slot's index pool (`DrawLists::pool`); each view then draws its region with one command, and its
//! cluster list only where a cluster did not fit the region (kept whole: slower, never wrong). On
//! lavapipe every draw costs its own setup: a view drew a dozen clusters.
//!
//! A cluster of a closed part seen from outside also drops its back faces (`clusters::closed`): hidden
//! behind the part's front faces, they were half the triangles a sensor drew in the hall of columns.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use glam::{Vec3, Vec4, Vec4Swizzles as _};

use crate::gpu_types::{CullPush, GpuSensorView};
use crate::shaders;
use crate::vk::{Access, Buffer, ComputeKernel, Device, Encoder, barrier, compute::groups_for};

/// Bytes of the kept list's header: the dispatch (`uvec4`).
pub const KEPT_HEADER_BYTES: u64 = 16;
/// Workgroup size of both steps.
const GROUP: u32 = 64;

/// What one triangle pass reads and writes.
pub struct TriangleBindings<'a> {
    pub views: &'a Buffer,
    /// The clusters' vertices and indices.
    pub vertices: &'a Buffer,
    pub indices: &'a Buffer,
    /// The slot's index pool, a region per view (usage: index and storage).
    pub pool: &'a Buffer,
    pub commands: &'a Buffer,
    pub counts: &'a Buffer,
    /// [`KEPT_HEADER_BYTES`], then a `u32` per command slot (usage: storage, indirect, transfer destination).
    pub kept: &'a Buffer,
    /// A `GpuDrawCommand` per view over its region of the pool, and a `u32` per view, how many of it to
    /// draw: 1, or 0 where empty (usage: storage, indirect).
    pub regions: &'a Buffer,
    pub region_draws: &'a Buffer,
}

/// The triangle pass: run by `passes::cull::CullPass` after its walk, on the commands the walk wrote.
pub struct CullTriangles {
    kernel: ComputeKernel,
}

impl CullTriangles {
    /// `sets`: one per batch in flight.
    pub fn new(device: &Arc<Device>, sets: u32) -> Result<Self> {
        let bindings: Vec<_> = (0..9).map(|b| (b, vk::DescriptorType::STORAGE_BUFFER)).collect();
        let push = size_of::<CullPush>() as u32;
        Ok(Self { kernel: ComputeKernel::new(device, shaders::CULL_TRIANGLES_COMP, &bindings, push, sets)? })
    }

    /// Binds set `set` (call while its work is not in flight).
    pub fn bind(&self, device: &Device, set: usize, b: &TriangleBindings<'_>) {
        self.kernel
            .writer(set)
            .storage_buffer(0, b.views)
            .storage_buffer(1, b.vertices)
            .storage_buffer(2, b.indices)
            .storage_buffer(3, b.commands)
            .storage_buffer(4, b.counts)
            .storage_buffer(5, b.kept)
            .storage_buffer(6, b.regions)
            .storage_buffer(7, b.pool)
            .storage_buffer(8, b.region_draws)
            .apply(device);
    }

    /// Records the pass over the commands listed in `kept` (the walk's, made visible to compute and
    /// indirect reads by the caller), an invocation per command as the walk counted them, then each view's
    /// list count.
    pub fn record(&self, enc: &Encoder<'_>, set: usize, kept: &Buffer, push: &CullPush) {
        self.kernel.dispatch_indirect(enc, set, &CullPush { step: 0, ..*push }, (kept, 4));
        barrier::global(enc, &[Access::ComputeWrite], &[Access::ComputeWrite]);
        self.kernel.dispatch(enc, set, &CullPush { step: 1, ..*push }, [groups_for(push.views, GROUP), 1, 1]);
    }
}

/// Window-space slack (texels) of the coverage test: the rasterizer snaps vertices to 1/256 texel and the
/// vertex shader may round its transform differently from this pass.
pub const COVER_SLACK: f32 = 1.0 / 64.0;

/// Whether `view` (of `rd × rd` texels) may rasterize a fragment of the triangle with world-space corners
/// `p`. False only where the triangle lies wholly outside one of the view's clip planes or frustum sides,
/// wholly nearer than the near plane, or, wholly in front of the eye, where its window-space box holds no
/// texel centre (within [`COVER_SLACK`]): such a triangle covers no sample, so dropping it leaves the maps
/// as they are. The twin of `glsl/cull_triangles.comp`'s `may_cover`.
pub fn may_cover(view: &GpuSensorView, rd: u32, p: [Vec3; 3]) -> bool {
    let outside = |d: [f32; 3]| d.iter().all(|&d| d < 0.0);
    if view.clip.iter().any(|plane| outside(p.map(|q| plane.xyz().dot(q) + plane.w))) {
        return false;
    }
    let c: [Vec4; 3] = p.map(|q| view.view_proj * q.extend(1.0));
    // x, y within ±w; z ≤ w (reversed Z: z = w on the near plane).
    let sides = [c.map(|c| c.w - c.x), c.map(|c| c.w + c.x), c.map(|c| c.w - c.y), c.map(|c| c.w + c.y)];
    if sides.into_iter().any(outside) || outside(c.map(|c| c.w - c.z)) {
        return false;
    }
    if c.iter().any(|c| c.w <= 0.0) {
        return true;
    }
    let window = c.map(|c| (c.xy() / c.w * 0.5 + 0.5) * rd as f32);
    let lo = window[0].min(window[1]).min(window[2]);
    let hi = window[0].max(window[1]).max(window[2]);
    holds_centre(lo.x, hi.x) && holds_centre(lo.y, hi.y)
}

/// Whether the triangle with world-space corners `p` turns its front (counter-clockwise) towards `eye`. Where
/// the culling pass marked a cluster's closed part as seen from outside (`passes::cull::back_hidden`), the
/// triangles that do not are dropped: the part's front faces hide them. The twin of
/// `glsl/cull_triangles.comp`'s `faces`.
pub fn faces(eye: Vec3, p: [Vec3; 3]) -> bool {
    (p[1] - p[0]).cross(p[2] - p[0]).dot(eye - p[0]) > 0.0
}

/// Whether `[lo, hi]` (window coordinates, widened by [`COVER_SLACK`]) holds a texel centre `k + 0.5`.
fn holds_centre(lo: f32, hi: f32) -> bool {
    (hi - 0.5 + COVER_SLACK).floor() >= (lo - 0.5 - COVER_SLACK).ceil()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A view looking down −z from the origin, 90° wide, near plane 0.1, reversed Z, nothing clipped.
    fn view() -> GpuSensorView {
        let proj = crate::scene::camera::projection(std::f32::consts::FRAC_PI_2, 1.0, 0.1);
        GpuSensorView { view_proj: proj, clip: [Vec4::W; 4], ..Default::default() }
    }

    #[test]
    fn a_triangle_between_texel_centres_is_dropped_and_one_over_a_centre_kept() {
        let (v, rd) = (view(), 32);
        // At depth 1 the view spans x in [-1, 1] over 32 texels: texel centres at -1 + (k + 0.5) / 16.
        let at = |x: f32, y: f32| Vec3::new(x, y, -1.0);
        let centre = -1.0 + 16.5 / 16.0;
        let small = 0.01;
        // Around a centre: kept.
        assert!(may_cover(
            &v,
            rd,
            [at(centre - small, centre - small), at(centre + small, centre), at(centre, centre + small)]
        ));
        // Between centres (a texel corner, 1/32 texel wide): dropped.
        let corner = -1.0 + 16.0 / 16.0;
        let tiny = 0.001;
        assert!(!may_cover(&v, rd, [at(corner, corner), at(corner + tiny, corner), at(corner, corner + tiny)]));
        // A long sliver along x between two rows of centres: dropped too.
        assert!(!may_cover(&v, rd, [at(-0.9, corner), at(0.9, corner), at(0.9, corner + tiny)]));
    }

    #[test]
    fn a_triangle_outside_a_side_or_behind_a_clip_plane_is_dropped() {
        let v = view();
        let tri = |dx: f32| [Vec3::new(dx, 0.0, -1.0), Vec3::new(dx + 0.5, 0.0, -1.0), Vec3::new(dx, 0.5, -1.0)];
        assert!(may_cover(&v, 32, tri(0.0)));
        assert!(!may_cover(&v, 32, tri(1.1)), "right of the frustum");
        let clipped = GpuSensorView { clip: [Vec4::new(0.0, -1.0, 0.0, -0.6), Vec4::W, Vec4::W, Vec4::W], ..v };
        assert!(!may_cover(&clipped, 32, tri(0.0)), "below y = -0.6 is kept, the triangle lies above");
        // Nearer than the near plane, and straddling the eye's plane (kept: its window box is unbounded).
        let near = [Vec3::new(0.0, 0.0, -0.05), Vec3::new(0.01, 0.0, -0.05), Vec3::new(0.0, 0.01, -0.05)];
        assert!(!may_cover(&v, 32, near));
        let across = [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.1, 0.0, -1.0), Vec3::new(0.0, 0.1, -1.0)];
        assert!(may_cover(&v, 32, across));
    }
}
