//! The supersampling's resolve (docs/DESIGN.md §11, step 8 of §3): after composition, each supersampled
//! pixel becomes the mean of `Le + Kd·R` over its sub-pixel samples, each sample's R its donor's final R
//! with the exact light recomputed at the sample. Shader: `glsl/resolve.comp`; CPU twin:
//! [`crate::supersample::resolve_cpu`].

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use crate::gpu_scene::GpuScene;
use crate::gpu_types::{GpuSubSample, GpuSupersampledPixel, ResolvePush};
use crate::passes::gbuffer::GBuffer;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, compute::spilled, transfer};

pub struct ResolvePass {
    kernel: ComputeKernel,
    /// What the last [`ResolvePass::bind`] uploaded (kept alive until the next), and its dispatch.
    inputs: Option<(Buffer, Buffer)>,
    push: Option<ResolvePush>,
}

/// What a resolve reads and writes besides its samples.
pub struct ResolveTargets<'a> {
    /// Every pixel's final R (read), the final image (its supersampled pixels written) and R averaged over
    /// each supersampled pixel's samples (written, one per pixel, in order).
    pub composed: &'a Buffer,
    pub image: &'a Buffer,
    pub resolved: &'a Buffer,
    pub gbuffer: &'a GBuffer,
    pub scene: &'a GpuScene,
}

impl ResolvePass {
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let (storage, image) = (vk::DescriptorType::STORAGE_BUFFER, vk::DescriptorType::STORAGE_IMAGE);
        let bindings: Vec<_> = (0..10).map(|b| (b, if b == 5 || b == 6 { image } else { storage })).collect();
        let kernel = ComputeKernel::new(device, shaders::RESOLVE_COMP, &bindings, size_of::<ResolvePush>() as u32, 1)?;
        Ok(Self { kernel, inputs: None, push: None })
    }

    /// Uploads the supersampled `pixels` (with their exact emission) and their `samples`
    /// (`supersample::SAMPLES` each) and binds the
    /// targets (call while the GPU is idle). `exact`: the light groups' light is computed at each sample
    /// (sensors lifted by `bias`). A sample that leaves the scene carries the sky it sees in its albedo.
    pub fn bind(
        &mut self,
        device: &Arc<Device>,
        (pixels, samples): (&[GpuSupersampledPixel], &[GpuSubSample]),
        t: ResolveTargets<'_>,
        (exact, bias): (bool, f32),
    ) -> Result<()> {
        (self.inputs, self.push) = (None, None);
        if pixels.is_empty() {
            return Ok(());
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let pixel_buffer = transfer::upload(device, "supersampled pixels", pixels, usage)?;
        let sample_buffer = transfer::upload(device, "sub-pixel samples", samples, usage)?;
        (self.kernel.writer(0))
            .storage_buffer(0, &pixel_buffer)
            .storage_buffer(1, &sample_buffer)
            .storage_buffer(2, t.composed)
            .storage_buffer(3, t.image)
            .storage_buffer(4, t.resolved)
            .storage_image(5, t.gbuffer.position.view)
            .storage_image(6, t.gbuffer.normal.view)
            .storage_buffer(7, &t.scene.emitters)
            .storage_buffer(8, &t.scene.chunks)
            .storage_buffer(9, &t.scene.groups)
            .apply(device);
        self.push = Some(ResolvePush {
            width: t.gbuffer.size.width,
            count: pixels.len() as u32,
            samples: (samples.len() / pixels.len()) as u32,
            groups: t.scene.lights.groups.len() as u32,
            bias,
            exact: exact as u32,
            _pad: [0; 2],
        });
        self.inputs = Some((pixel_buffer, sample_buffer));
        Ok(())
    }

    /// Records the resolve (nothing when no pixel is supersampled). The composition's writes must be
    /// visible.
    pub fn record(&self, enc: &Encoder<'_>) {
        let Some(push) = &self.push else { return };
        // One invocation per pixel; workgroups beyond the per-dimension limit spill into y.
        self.kernel.dispatch(enc, 0, push, spilled(enc, push.count.div_ceil(64)));
    }
}
