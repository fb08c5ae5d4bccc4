//! Interpolation pass (paper §III-G, docs/DESIGN.md §3 step 5): fills the quads the refinement accepted from
//! their sensed corners. Shaders, one workgroup per quad: `glsl/interpolate.comp` (bilinear in R; CPU twin
//! [`crate::sensors::refine::interpolate_cpu`]) and, with the exact estimator's visibilities,
//! `glsl/interpolate_exact.comp` (each light group's unoccluded light computed per pixel, only its
//! visibility and the rest interpolated; CPU twin [`crate::sensors::refine::interpolate_exact_cpu`]).

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use crate::gpu_scene::GpuScene;
use crate::gpu_types::{ExactInterpolatePush, GpuQuad, ImagePush, MAX_GROUPS};
use crate::passes::gbuffer::GBuffer;
use crate::scene::ImageSize;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, transfer};

/// Maps interpolated alike: the radiance map and its indirect part.
const MAPS: u32 = 2;

pub struct InterpolatePass {
    kernel: ComputeKernel,
    exact: ComputeKernel,
    /// Holds the quads bound by the last [`InterpolatePass::bind`], and their corners' visibilities.
    quads: Option<Buffer>,
    corners: Option<Buffer>,
    count: u32,
    /// With [`Exact`]: light groups and the sensors' lift.
    exact_push: Option<(u32, f32)>,
}

/// What the exact interpolation reads besides the maps: the corners' measured visibilities, each
/// `[quad][corner 00, 10, 01, 11][group of MAX_GROUPS]` (< 0: not measured), and where each pixel is.
pub struct Exact<'a> {
    pub corner_visibility: &'a [[[f32; MAX_GROUPS]; 4]],
    pub gbuffer: &'a GBuffer,
    pub scene: &'a GpuScene,
    pub bias: f32,
}

impl InterpolatePass {
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let kernel = ComputeKernel::new(
            device,
            shaders::INTERPOLATE_COMP,
            &[(0, storage), (1, storage)],
            size_of::<ImagePush>() as u32,
            MAPS,
        )?;
        let image = vk::DescriptorType::STORAGE_IMAGE;
        let exact_bindings = [
            (0, storage),
            (1, storage),
            (2, storage),
            (3, storage),
            (4, image),
            (5, image),
            (6, storage),
            (7, storage),
            (8, storage),
        ];
        let exact = ComputeKernel::new(
            device,
            shaders::INTERPOLATE_EXACT_COMP,
            &exact_bindings,
            size_of::<ExactInterpolatePush>() as u32,
            1,
        )?;
        Ok(Self { kernel, exact, quads: None, corners: None, count: 0, exact_push: None })
    }

    /// Uploads `quads` and binds the maps they fill, the radiance map and its indirect part (call while the
    /// GPU is idle). With `exact`, R is filled by the exact interpolation from the corners' indirect part and
    /// visibilities (one per quad, in `quads`' order), the indirect part bilinearly as without.
    pub fn bind(
        &mut self,
        device: &Arc<Device>,
        quads: &[GpuQuad],
        maps: [&Buffer; MAPS as usize],
        exact: Option<Exact<'_>>,
    ) -> Result<()> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let buffer = transfer::upload(device, "interpolated quads", quads, usage)?;
        for (set, map) in maps.into_iter().enumerate() {
            self.kernel.writer(set).storage_buffer(0, &buffer).storage_buffer(1, map).apply(device);
        }
        self.exact_push = None;
        self.corners = None;
        if let Some(e) = exact.filter(|_| !quads.is_empty()) {
            assert_eq!(e.corner_visibility.len(), quads.len(), "one corner visibility per quad");
            let corners = transfer::upload(device, "corner visibilities", e.corner_visibility, usage)?;
            (self.exact.writer(0))
                .storage_buffer(0, &buffer)
                .storage_buffer(1, maps[0])
                .storage_buffer(2, maps[1])
                .storage_buffer(3, &corners)
                .storage_image(4, e.gbuffer.position.view)
                .storage_image(5, e.gbuffer.normal.view)
                .storage_buffer(6, &e.scene.emitters)
                .storage_buffer(7, &e.scene.chunks)
                .storage_buffer(8, &e.scene.groups)
                .apply(device);
            self.exact_push = Some((e.scene.lights.groups.len() as u32, e.bias));
            self.corners = Some(corners);
        }
        self.quads = Some(buffer);
        self.count = quads.len() as u32;
        Ok(())
    }

    pub fn record(&self, enc: &Encoder<'_>, size: ImageSize) {
        if self.count == 0 {
            return;
        }
        // Workgroups beyond the per-dimension limit spill into y; the shader skips indices past `count`.
        let max_x = enc.device().adapter.limits.max_compute_work_group_count[0];
        let groups = [self.count.min(max_x), self.count.div_ceil(max_x), 1];
        let push = ImagePush { width: size.width, height: size.height, radius: 0, count: self.count };
        // The radiance map's corners are sensed pixels, which neither dispatch writes: no barrier between.
        match self.exact_push {
            Some((light_groups, bias)) => {
                let exact = ExactInterpolatePush { width: size.width, count: self.count, groups: light_groups, bias };
                self.exact.dispatch(enc, 0, &exact, groups);
            }
            None => self.kernel.dispatch(enc, 0, &push, groups),
        }
        self.kernel.dispatch(enc, 1, &push, groups);
    }
}
