//! Interpolation pass (paper §III-G, docs/DESIGN.md §3 step 5): fills the quads the refinement accepted from
//! their sensed corners. Shaders: `glsl/interpolate.comp` (bilinear in R, one workgroup per quad; CPU twin
//! [`crate::sensors::refine::interpolate_cpu`]) and, with the exact estimator's visibilities,
//! `glsl/interpolate_exact.comp` (each light group's unoccluded light computed per pixel, only its
//! visibility and the rest interpolated, one invocation per pixel to fill; CPU twin
//! [`crate::sensors::refine::interpolate_exact_cpu`]).

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use crate::gpu_scene::GpuScene;
use crate::gpu_types::{ExactInterpolatePush, GpuQuad, ImagePush, MAX_GROUPS};
use crate::passes::gbuffer::GBuffer;
use crate::scene::ImageSize;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, compute::spilled, transfer};

/// Maps interpolated alike: the radiance map and its indirect part.
const MAPS: u32 = 2;

pub struct InterpolatePass {
    kernel: ComputeKernel,
    exact: ComputeKernel,
    /// Holds the quads bound by the last [`InterpolatePass::bind`], and their corners' visibilities.
    quads: Option<Buffer>,
    corners: Option<Buffer>,
    fills: Option<Buffer>,
    count: u32,
    /// With [`Exact`]: what its dispatch is given.
    exact_push: Option<ExactInterpolatePush>,
}

/// What the exact interpolation reads besides the maps: the corners' measured visibilities, each
/// `[quad][corner 00, 10, 01, 11][group of MAX_GROUPS]` (< 0: not measured), where each pixel is, and which
/// pixels were sensed (the others of each quad's own are filled).
pub struct Exact<'a> {
    pub sensed: &'a dyn Fn(usize) -> bool,
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
            (9, storage),
        ];
        let exact = ComputeKernel::new(
            device,
            shaders::INTERPOLATE_EXACT_COMP,
            &exact_bindings,
            size_of::<ExactInterpolatePush>() as u32,
            1,
        )?;
        Ok(Self { kernel, exact, quads: None, corners: None, fills: None, count: 0, exact_push: None })
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
        (self.exact_push, self.corners, self.fills) = (None, None, None);
        if let Some(e) = exact.filter(|_| !quads.is_empty()) {
            assert_eq!(e.corner_visibility.len(), quads.len(), "one corner visibility per quad");
            let width = e.gbuffer.size.width;
            let fills: Vec<[u32; 2]> = (quads.iter().enumerate())
                .flat_map(|(k, q)| {
                    (q.y0..=q.own_y1).flat_map(move |y| (q.x0..=q.own_x1).map(move |x| [y * width + x, k as u32]))
                })
                .filter(|&[i, _]| !(e.sensed)(i as usize))
                .collect();
            let corners = transfer::upload(device, "corner visibilities", e.corner_visibility, usage)?;
            // (Never an empty buffer: a quad of corners alone fills nothing, and count 0 reads nothing.)
            let listed: &[[u32; 2]] = if fills.is_empty() { &[[0, 0]] } else { &fills };
            let fill_list = transfer::upload(device, "pixels to fill", listed, usage)?;
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
                .storage_buffer(9, &fill_list)
                .apply(device);
            let groups = e.scene.lights.groups.len() as u32;
            self.exact_push = Some(ExactInterpolatePush { width, count: fills.len() as u32, groups, bias: e.bias });
            (self.corners, self.fills) = (Some(corners), Some(fill_list));
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
        let groups = spilled(enc, self.count);
        let push = ImagePush { width: size.width, height: size.height, radius: 0, count: self.count };
        // The radiance map's corners are sensed pixels, which neither dispatch writes: no barrier between.
        match &self.exact_push {
            Some(exact) => self.exact.dispatch(enc, 0, exact, spilled(enc, exact.count.div_ceil(64))),
            None => self.kernel.dispatch(enc, 0, &push, groups),
        }
        self.kernel.dispatch(enc, 1, &push, groups);
    }
}
