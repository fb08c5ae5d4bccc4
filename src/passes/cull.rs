//! Cluster culling pass (docs/DESIGN.md §9): per batch, for every sensor view, the clusters of the LOD
//! hierarchy it sees at the level of detail its texels need, written as indexed indirect draws (one list
//! per view, `max_per_view` slots each, and a count per view: `vkCmdDrawIndexedIndirectCount` reads them,
//! so the host records the same work whatever the scene). Shader: `glsl/cull.comp`, one invocation per
//! (cluster, view). CPU twin: [`keeps`].
//!
//! A view's count may exceed `max_per_view`: the commands past it are not written, and the count says so.
//! The batch runner sizes `max_per_view` by `clusters::max_selected`, so that this cannot happen, and
//! checks every count it reads back.
//!
//! After the `views` draw counts, the counts buffer holds each view's triangles drawn (statistics, tests).

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use glam::{Mat4, Vec4, Vec4Swizzles as _};

use crate::gpu_types::{CLUSTER_EMITTER, CullPush, GpuCluster, GpuSensor, GpuSensorView, VIEW_EMITTERS_ONLY};
use crate::shaders;
use crate::vk::{Access, Buffer, ComputeKernel, Device, Encoder, barrier, compute::groups_for};

const GROUP: u32 = 64;

/// What one culling dispatch reads and writes.
pub struct CullBindings<'a> {
    pub clusters: &'a Buffer,
    pub views: &'a Buffer,
    pub sensors: &'a Buffer,
    /// `views × max_per_view` `GpuDrawCommand`s (usage: storage and indirect).
    pub commands: &'a Buffer,
    /// Two `u32` per view: draws, then triangles (usage: storage, indirect and transfer destination: it is
    /// cleared here).
    pub counts: &'a Buffer,
}

pub struct CullPass {
    kernel: ComputeKernel,
}

impl CullPass {
    /// `sets`: one per batch in flight.
    pub fn new(device: &Arc<Device>, sets: u32) -> Result<Self> {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let bindings: Vec<_> = (0..5).map(|b| (b, storage)).collect();
        let kernel = ComputeKernel::new(device, shaders::CULL_COMP, &bindings, size_of::<CullPush>() as u32, sets)?;
        Ok(Self { kernel })
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
            .apply(device);
    }

    /// Records: clear the counts, cull, and make the commands and counts visible to indirect draws.
    /// `zero_commands`: also clear every command first, for draws that read all `max_per_view` of a view
    /// (no `drawIndirectCount`): the unused ones then draw nothing.
    pub fn record(
        &self,
        enc: &Encoder<'_>,
        set: usize,
        counts: &Buffer,
        zero_commands: Option<&Buffer>,
        push: &CullPush,
    ) {
        barrier::global(enc, &[Access::IndirectRead], &[Access::TransferWrite]);
        enc.fill(counts, 0);
        if let Some(commands) = zero_commands {
            enc.fill(commands, 0);
        }
        barrier::global(enc, &[Access::TransferWrite], &[Access::ComputeWrite]);
        let groups = [groups_for(push.clusters, GROUP), push.views, 1];
        if push.clusters > 0 && push.views > 0 {
            self.kernel.dispatch(enc, set, push, groups);
        }
        barrier::global(enc, &[Access::ComputeWrite], &[Access::IndirectRead]);
    }
}

/// The CPU twin of `glsl/cull.comp`: whether `view` (of `sensor`) draws `cluster`.
pub fn keeps(cluster: &GpuCluster, view: &GpuSensorView, sensor: &GpuSensor, rd: u32, near: f32) -> bool {
    let eye = sensor.origin.xyz();
    let sphere = cluster.sphere;
    let outside = |plane: Vec4| plane.xyz().dot(sphere.xyz()) + plane.w < -sphere.w * plane.xyz().length();
    if sensor.n.xyz().dot(sphere.xyz() - eye) < -sphere.w {
        return false;
    }
    if view.flags & VIEW_EMITTERS_ONLY != 0 && cluster.flags & CLUSTER_EMITTER == 0 {
        return false;
    }
    if view.clip.iter().any(|&p| outside(p)) {
        return false;
    }
    let m: Mat4 = view.view_proj;
    let (r0, r1, w) = (m.row(0), m.row(1), m.row(3));
    if [w + r0, w - r0, w + r1, w - r1].into_iter().any(outside) {
        return false;
    }
    let tau = 1.0 / (rd as f32 * r0.xyz().length().max(r1.xyz().length()));
    let projected = |bounds: Vec4, error: f32| {
        if error == 0.0 { 0.0 } else { error / (bounds.xyz().distance(eye) - bounds.w).max(near) }
    };
    projected(cluster.own, cluster.errors.x) <= tau && projected(cluster.parent, cluster.errors.y) > tau
}

/// The clusters as the pass reads them (defined beside the buffers it fills).
pub use crate::gpu_scene::gpu_clusters;
