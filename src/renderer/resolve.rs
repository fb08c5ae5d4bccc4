//! The supersampled pixels resolved after composition (docs/DESIGN.md §11), a slice of
//! [`supersample::SLICE`] pixels at a time: their samples cast again on the host, each given its donor and
//! visibilities, uploaded and averaged on the GPU (`passes::resolve`).

use anyhow::Result;
use glam::{Vec3, Vec4};

use super::Renderer;
use super::targets::{Targets, map_buffer};
use crate::gbuffer::GBufferData;
use crate::gbuffer::cast::Visible;
use crate::passes::resolve::ResolveTargets;
use crate::scene::{ImageSize, SurfaceId};
use crate::sensors::refine::Visibility;
use crate::supersample::{self, CacheValue, Plan, SAMPLES, SLICE, SubSampleCache, SubSampleLight};
use crate::vk::{Access, barrier, transfer};

impl Renderer {
    /// Resolves `plan`'s pixels over the composed image in `targets` (the centres' G-buffer `g`): writes
    /// their image and returns, per pixel, R averaged over its samples on a surface, and where most of its
    /// samples show another surface than its centre, what the first of those sees (its G-buffer AOVs then
    /// describe one surface, the one most of the pixel shows). `light`, with the exact interpolation: every pixel's visibilities (as interpolated),
    /// light hint, and each light group's hint bits; the sensors' lift and near distance `offsets`.
    /// `cache_values`: with global illumination, the radiance cache's values the sensors read.
    pub(super) fn resolve_supersampled(
        &mut self,
        plan: &Plan,
        (g, targets): (&GBufferData, &Targets),
        light: Option<(&[Visibility], &[u64], &[u64])>,
        cache_values: Option<&[Vec4]>,
        (bias, near): (f32, f32),
        background: Vec3,
    ) -> Result<(Vec<Vec4>, Vec<Option<Visible>>)> {
        let (mut resolved, mut majority) = (Vec::with_capacity(plan.pixels.len()), Vec::new());
        if plan.pixels.is_empty() {
            return Ok((resolved, majority));
        }
        let device = self.device.clone();
        let slice = plan.pixels.len().min(SLICE) as u32;
        let averaged = map_buffer(&device, "supersampled radiance", ImageSize { width: slice, height: 1 })?;
        for start in (0..plan.pixels.len()).step_by(SLICE) {
            let range = start..(start + SLICE).min(plan.pixels.len());
            let taken = plan.samples(&self.host, &self.bvh, g, range.clone());
            let sample_light = (light.zip(self.light_points.as_deref()).zip(self.shadow_points.as_ref())).map(
                |(((visibility, hints, bits), points), shadow)| SubSampleLight {
                    visibility,
                    hints,
                    bvh: &self.bvh,
                    points,
                    bits,
                    shadow,
                    bias,
                    near,
                },
            );
            let read = self.cache.as_ref().zip(cache_values).map(|((cache, _), values)| {
                let (eye, mesh) = (self.host.camera.eye, &self.host.mesh);
                move |p: Vec3, surface: SurfaceId, front: bool| {
                    let index = cache.lookup_from(p, eye, surface, front);
                    let entry = cache.entries.get(index);
                    let kd = cache.albedo.get(index).copied().unwrap_or_else(|| mesh.surface_albedo(surface));
                    let r = values[index].truncate() / kd;
                    CacheValue {
                        index,
                        r: Vec3::select(kd.cmpgt(Vec3::ZERO), r, Vec3::ZERO),
                        sensed_at: entry.map(|e| (e.point, e.normal)),
                    }
                }
            });
            let sample_cache = read.as_ref().map(|read| SubSampleCache { read, lights: &self.scene.lights });
            let mut samples = supersample::sub_samples(g, (plan, range.clone(), &taken), sample_light, sample_cache);
            let camera = &self.host.camera;
            supersample::carry_sky(&mut samples, &taken.points, |at| match &self.host.sky {
                Some(sky) => sky.radiance(camera.ray(at.x, at.y, g.size.width, g.size.height).dir),
                None => background,
            });
            let t = ResolveTargets {
                composed: &targets.composed,
                image: &targets.image,
                resolved: &averaged,
                gbuffer: &targets.gbuffer,
                scene: &self.scene,
            };
            let exact = light.is_some();
            self.passes.resolve.bind(&device, (&plan.gpu_pixels(range.clone()), &samples), t, (exact, bias))?;
            device.submit_and_wait(|enc| {
                barrier::global(enc, &[Access::ComputeWrite, Access::TransferWrite], &[Access::ComputeWrite]);
                self.passes.resolve.record(enc);
                Ok(())
            })?;
            resolved.extend(transfer::read_buffer::<Vec4>(&device, &averaged, range.len())?);
            for (n, (ids, weights)) in taken.seen.surface.chunks(SAMPLES).zip(taken.weights.chunks(SAMPLES)).enumerate()
            {
                let id = supersample::majority_id(ids, weights);
                let centre = g.surface[plan.pixels[range.start + n] as usize];
                majority.push((id != centre).then(|| {
                    let s = n * SAMPLES + ids.iter().position(|&i| i == id).unwrap_or(0);
                    let seen = &taken.seen;
                    Visible {
                        position: seen.position[s],
                        normal: seen.normal[s],
                        albedo: seen.albedo[s],
                        emission: seen.emission[s],
                        surface: id,
                    }
                }));
            }
        }
        Ok((resolved, majority))
    }
}
