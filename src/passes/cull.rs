//! Cluster culling pass (docs/DESIGN.md §9): per batch, for every sensor view, the clusters of the LOD
//! hierarchy it sees at the level of detail its texels need, written as indexed indirect draws (one list
//! per view, `max_per_view` slots each, and a count per view: `vkCmdDrawIndexedIndirectCount` reads them,
//! so the host records the same work whatever the scene). Shader: `glsl/cull.comp`. CPU twin: [`keeps`].
//!
//! It walks the clusters' bounding tree (`clusters::tree`) one depth per dispatch, so that a view's cost
//! follows what it selects rather than the hierarchy's size; each step queues the (node, view) pairs of the
//! next depth and counts the workgroups to take them, which the next step's indirect dispatch reads:
//!
//! ```text
//!   walk:  depth 0       depth 1        depth 2        …   (uvec4 each: pairs queued, groups, 1, 1)
//!   queue: [ depth 1: views × nodes(1) ][ depth 2: views × nodes(2) ] …   ((node, view) pairs)
//!   step 0: the root, every view ─▶ depth 1;  step d: depth d ─▶ depth d + 1 (leaves: draws)
//! ```
//!
//! Each (node, view) pair is queued at most once, so a depth's region holds all it can receive. A view's
//! draw count may exceed `max_per_view`: the commands past it are not written, and the count says so. The
//! batch runner sizes `max_per_view` by `clusters::max_selected`, so that this cannot happen, and checks
//! every count it reads back.
//!
//! The counts buffer holds [`COUNT_BLOCKS`] blocks of `views` `u32`: each view's draws in its list, its
//! triangles selected (statistics, tests), and for the triangle pass: its triangles drawn, the indices
//! reserved in its region of the pool, its clusters left whole, and the walk's draws (the triangle pass
//! zeroes the first block's count where it left no cluster whole, so that the list draws nothing).
//!
//! Then the triangle pass (`passes::cull_triangles`) takes every command the walk wrote, listed in the
//! `kept` buffer, and drops the triangles that cannot cover a texel of their view.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use glam::{Mat4, Vec3, Vec4, Vec4Swizzles as _};

use super::cull_triangles::{CullTriangles, TriangleBindings};
use crate::clusters;
use crate::gpu_scene::{TreeShape, bounds_from_gpu};
use crate::gpu_types::{
    CLUSTER_CLOSED, CLUSTER_EMITTER, CullPush, GpuCluster, GpuSensor, GpuSensorView, VIEW_EMITTERS_ONLY,
};
use crate::shaders;
use crate::vk::{Access, Buffer, ComputeKernel, Device, Encoder, barrier, compute::groups_for};

const GROUP: u32 = 64;
/// Blocks of per-view counts in the counts buffer.
pub const COUNT_BLOCKS: u64 = 6;

/// What one culling pass reads and writes.
pub struct CullBindings<'a> {
    pub clusters: &'a Buffer,
    /// The bounding tree: `GpuCullNode`s, and the leaves' cluster indices.
    pub nodes: &'a Buffer,
    pub items: &'a Buffer,
    pub views: &'a Buffer,
    pub sensors: &'a Buffer,
    /// `views × max_per_view` `GpuDrawCommand`s (usage: storage and indirect).
    pub commands: &'a Buffer,
    /// [`COUNT_BLOCKS`] `u32` per view (usage: storage, indirect and transfer destination: it is cleared
    /// here).
    pub counts: &'a Buffer,
    /// The walk's scratch: `TreeShape::queue_bytes` and `TreeShape::walk_bytes` (usage: storage; the walk
    /// also indirect and transfer destination).
    pub queue: &'a Buffer,
    pub walk: &'a Buffer,
    /// The commands written, for the triangle pass ([`TriangleBindings::kept`]).
    pub kept: &'a Buffer,
    /// The clusters' vertices and indices and the slot's index pool, for the triangle pass.
    pub vertices: &'a Buffer,
    pub indices: &'a Buffer,
    pub pool: &'a Buffer,
    /// Each view's command over its region of the pool, started by the walk, and its count of them.
    pub regions: &'a Buffer,
    pub region_draws: &'a Buffer,
}

pub struct CullPass {
    kernel: ComputeKernel,
    triangles: CullTriangles,
    tree: TreeShape,
}

impl CullPass {
    /// `sets`: one per batch in flight.
    pub fn new(device: &Arc<Device>, sets: u32, tree: TreeShape) -> Result<Self> {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let bindings: Vec<_> = (0..11).map(|b| (b, storage)).collect();
        let kernel = ComputeKernel::new(device, shaders::CULL_COMP, &bindings, size_of::<CullPush>() as u32, sets)?;
        Ok(Self { kernel, triangles: CullTriangles::new(device, sets)?, tree })
    }

    /// Binds set `set` (call while its work is not in flight).
    pub fn bind(&self, device: &Device, set: usize, b: &CullBindings<'_>) {
        self.kernel
            .writer(set)
            .storage_buffer(0, b.clusters)
            .storage_buffer(1, b.views)
            .storage_buffer(2, b.sensors)
            .storage_buffer(3, b.commands)
            .storage_buffer(4, b.counts)
            .storage_buffer(5, b.nodes)
            .storage_buffer(6, b.items)
            .storage_buffer(7, b.queue)
            .storage_buffer(8, b.walk)
            .storage_buffer(9, b.kept)
            .storage_buffer(10, b.regions)
            .apply(device);
        let triangles = TriangleBindings {
            views: b.views,
            vertices: b.vertices,
            indices: b.indices,
            pool: b.pool,
            commands: b.commands,
            counts: b.counts,
            kept: b.kept,
            regions: b.regions,
            region_draws: b.region_draws,
        };
        self.triangles.bind(device, set, &triangles);
    }

    /// Records: clear the counts and the walk, walk the tree one depth per dispatch, run the triangle pass
    /// on the commands written (where `push.region` gives it room), and make the commands, counts
    /// and indices visible to the draws. `push` gives the batch's views, selection and pool; the walk's own
    /// fields are filled in here. `zero_commands`: also clear every command first, for draws that read all
    /// `max_per_view` of a view (no `drawIndirectCount`): the unused ones then draw nothing.
    pub fn record(
        &self,
        enc: &Encoder<'_>,
        set: usize,
        (counts, walk, kept): (&Buffer, &Buffer, &Buffer),
        zero_commands: Option<&Buffer>,
        push: &CullPush,
    ) {
        barrier::global(enc, &[Access::IndirectRead, Access::IndexRead], &[Access::TransferWrite]);
        enc.fill(counts, 0);
        if let Some(commands) = zero_commands {
            enc.fill(commands, 0);
        }
        let depths = self.tree.per_depth.len();
        let start: Vec<u32> = (0..depths).flat_map(|_| [0, 0, 1, 1]).collect();
        enc.update(walk, &start);
        enc.update(kept, &[0, 0, 1, 1]);
        barrier::global(enc, &[Access::TransferWrite], &[Access::ComputeWrite]);
        // Where each depth's pairs start in the queue (depth 0, the root, is not queued).
        let capacity = |d: usize| push.views * self.tree.per_depth.get(d).copied().unwrap_or(0);
        let mut base = vec![0u32; depths + 1];
        for d in 1..depths {
            base[d + 1] = base[d] + capacity(d);
        }
        for step in 0..depths {
            let push = CullPush {
                root: self.tree.root,
                step: step as u32,
                in_base: base[step],
                out_base: base[step + 1],
                in_capacity: if step == 0 { push.views } else { capacity(step) },
                out_capacity: capacity(step + 1),
                ..*push
            };
            if step == 0 {
                self.kernel.dispatch(enc, set, &push, [groups_for(push.views, GROUP), 1, 1]);
            } else {
                barrier::global(enc, &[Access::ComputeWrite], &[Access::ComputeWrite, Access::IndirectRead]);
                self.kernel.dispatch_indirect(enc, set, &push, (walk, 16 * step as u64 + 4));
            }
        }
        if push.region > 0 {
            barrier::global(enc, &[Access::ComputeWrite], &[Access::ComputeWrite, Access::IndirectRead]);
            self.triangles.record(enc, set, kept, push);
        }
        let draws = [Access::IndirectRead, Access::IndexRead, Access::ComputeRead];
        barrier::global(enc, &[Access::ComputeWrite], &draws);
    }
}

/// The CPU twin of `glsl/cull.comp`: whether `view` (of `sensor`) draws `cluster`: [`sees`] its sphere, it
/// reaches above the sensor's tangent plane (its slab: a smooth surface's clusters around a sensor on it
/// lie below), and it is the level selected. The walk keeps exactly these: it enters a node only where
/// this could hold for a cluster below.
pub fn keeps(cluster: &GpuCluster, view: &GpuSensorView, sensor: &GpuSensor, rd: u32, near: f32) -> bool {
    let (eye, n) = (sensor.origin.xyz(), sensor.n.xyz());
    let tau = accepted_error(view, rd);
    sees(view, sensor, cluster.sphere, cluster.flags)
        && box_sees(view, sensor, cluster.box_min.xyz(), cluster.box_max.xyz())
        && clusters::reach(cluster.sphere.into(), cluster.slab.into(), n) >= n.dot(eye)
        && clusters::projected_error(&bounds_from_gpu(cluster.own_min, cluster.own_max), eye, near) <= tau
        && clusters::projected_error(&bounds_from_gpu(cluster.parent_min, cluster.parent_max), eye, near) > tau
}

/// The CPU twin of what `glsl/cull.comp` marks a kept cluster with (`KEPT_BACK_HIDDEN`): its part hides its
/// back faces from outside its box (closed, or capped by closed parts: `clusters::closed`), and the
/// sensor's eye lies outside that box by more than the near plane's distance, so no back face of it can
/// show (none is clipped open by the near plane either).
pub fn back_hidden(cluster: &GpuCluster, sensor: &GpuSensor, near: f32) -> bool {
    let (eye, margin) = (sensor.origin.xyz(), Vec3::splat(near));
    let outside = eye.cmplt(cluster.part_min.xyz() - margin).any() || eye.cmpgt(cluster.part_max.xyz() + margin).any();
    cluster.flags & CLUSTER_CLOSED != 0 && outside
}

/// Whether `view` may see anything within `sphere` (of something flagged `flags`): not wholly behind the
/// sensor's tangent plane, outside the view's side or clip planes, or (in an emitters-only view) no emitter.
pub fn sees(view: &GpuSensorView, sensor: &GpuSensor, sphere: Vec4, flags: u32) -> bool {
    let outside = |plane: Vec4| plane.xyz().dot(sphere.xyz()) + plane.w < -sphere.w * plane.xyz().length();
    if sensor.n.xyz().dot(sphere.xyz() - sensor.origin.xyz()) < -sphere.w {
        return false;
    }
    if view.flags & VIEW_EMITTERS_ONLY != 0 && flags & CLUSTER_EMITTER == 0 {
        return false;
    }
    let m: Mat4 = view.view_proj;
    let (r0, r1, w) = (m.row(0), m.row(1), m.row(3));
    !view.clip.iter().any(|&p| outside(p)) && ![w + r0, w - r0, w + r1, w - r1].into_iter().any(outside)
}

/// Whether `view` may see anything within the box `[lo, hi]`: it reaches above the sensor's tangent plane,
/// and inside every side and clip plane of the view (each plane's farthest corner of the box).
pub fn box_sees(view: &GpuSensorView, sensor: &GpuSensor, lo: Vec3, hi: Vec3) -> bool {
    let inside = |plane: Vec4| plane.xyz().dot(Vec3::select(plane.xyz().cmpge(Vec3::ZERO), hi, lo)) + plane.w >= 0.0;
    let (n, origin) = (sensor.n.xyz(), sensor.origin.xyz());
    let m: Mat4 = view.view_proj;
    let (r0, r1, w) = (m.row(0), m.row(1), m.row(3));
    inside(n.extend(-n.dot(origin)))
        && view.clip.iter().all(|&p| inside(p))
        && [w + r0, w - r0, w + r1, w - r1].into_iter().all(inside)
}

/// The error (radians) a view accepts: half its centre texel, `1 / (rd · scale)`.
pub fn accepted_error(view: &GpuSensorView, rd: u32) -> f32 {
    let m: Mat4 = view.view_proj;
    1.0 / (rd as f32 * m.row(0).xyz().length().max(m.row(1).xyz().length()))
}

/// The clusters and their tree as the pass reads them (defined beside the buffers they fill).
pub use crate::gpu_scene::{gpu_clusters, gpu_cull_nodes};
