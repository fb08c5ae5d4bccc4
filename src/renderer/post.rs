//! After the sensing, on the GPU in one submission: interpolation (each light group's light per pixel with
//! the exact interpolation), the id-constrained filter, composition; then the supersampled pixels resolved
//! a slice at a time (docs/DESIGN.md §11) and their AOVs taken from the surface most of their samples show.

use std::time::{Duration, Instant};

use anyhow::Result;
use glam::Vec4;

use super::Renderer;
use super::sensing::Rounds;
use super::targets::Targets;
use crate::gbuffer::GBufferData;
use crate::params::{Antialiasing, FrameParams};
use crate::passes::interpolate;
use crate::sensors::refine;
use crate::supersample;
use crate::vk::{Access, barrier, transfer};

/// What the post passes made of a render.
pub(super) struct Post {
    /// `Le + albedo·R`.
    pub(super) image: Vec<Vec4>,
    /// R, interpolated and filtered; a supersampled pixel's the mean over its samples on a surface.
    pub(super) radiance: Vec<Vec4>,
    /// The G-buffer, but where most of a supersampled pixel's samples show another surface than its centre.
    pub(super) gbuffer: GBufferData,
    /// The pixels supersampled, in the order resolved.
    pub(super) supersampled: Vec<u32>,
    /// The host's time resolving them.
    pub(super) supersample_time: Duration,
}

impl Renderer {
    /// Interpolates, filters and composes what `rounds` sensed into `targets`, then resolves the
    /// supersampled pixels. `global_illumination`: the maps hold an indirect part, filtered apart where its
    /// radius is not R's; `sky_map`: the pixels without a surface show the sky map's pixels.
    pub(super) fn post(
        &mut self,
        targets: &Targets,
        mut g: GBufferData,
        rounds: &mut Rounds,
        frame: &FrameParams,
        global_illumination: bool,
        sky_map: bool,
    ) -> Result<Post> {
        let device = self.device.clone();
        let size = g.size;
        let pixels = size.width as usize * size.height as usize;
        let mut plan = std::mem::take(&mut rounds.plan);
        let (bias, _) = self.offsets();
        let (sensed, t) = (&targets.sensed, &targets);
        let Rounds { refinement, visibility, exact_interpolation, .. } = rounds;
        let exact_interpolation = *exact_interpolation;
        let quads = refinement.interpolated();
        let corner_visibility =
            if exact_interpolation { refine::corner_visibility(visibility, size.width, quads) } else { Vec::new() };
        let sensed_pixel = |i: usize| refinement.is_sensed(i);
        let exact_light = exact_interpolation.then(|| interpolate::Exact {
            sensed: &sensed_pixel,
            corner_visibility: &corner_visibility,
            gbuffer: &targets.gbuffer,
            scene: &self.scene,
            bias,
        });
        self.passes.interpolate.bind(&device, quads, [&sensed.radiance, &sensed.indirect], exact_light)?;
        let (ids, masks) = (&t.gbuffer.surface, &t.light_masks);
        // The indirect part apart: with global illumination and the exact estimator (whose main layers hold
        // only it), where its radius is R's own it is not (R's filter already does it).
        let apart =
            global_illumination && self.estimate.groups > 0 && frame.indirect_filter_radius != frame.filter_radius;
        self.passes.filter.bind(&device, 0, (&sensed.radiance, &t.filtered), ids, masks);
        self.passes.filter.bind(&device, 1, (&sensed.indirect, &t.indirect_at_r), ids, masks);
        self.passes.filter.bind(&device, 2, (&sensed.indirect, &t.indirect_own), ids, masks);
        self.passes.compose.bind(
            &device,
            [&t.filtered, &t.indirect_at_r, &t.indirect_own],
            [&t.image, &t.composed],
            &t.gbuffer,
            &t.sky,
        );
        device.submit_and_wait(|enc| {
            barrier::global(enc, &[Access::ComputeWrite, Access::TransferWrite], &[Access::ComputeWrite]);
            self.passes.interpolate.record(enc, size);
            barrier::global(enc, &[Access::ComputeWrite], &[Access::ComputeWrite]);
            self.passes.filter.record(enc, 0, size, frame.filter_radius);
            if apart {
                self.passes.filter.record(enc, 1, size, frame.filter_radius);
                self.passes.filter.record(enc, 2, size, frame.indirect_filter_radius);
            }
            barrier::global(enc, &[Access::ComputeWrite], &[Access::ComputeWrite]);
            self.passes.compose.record(enc, size, apart, (!sky_map).then_some(frame.background));
            Ok(())
        })?;
        // The supersampled pixels, a slice at a time: their samples' R from their donors, the mean over each.
        let start_samples = Instant::now();
        let everywhere = (exact_interpolation && frame.aa == Antialiasing::On).then(|| {
            refine::visibility_everywhere(visibility, size.width, refinement.interpolated(), |i| {
                refinement.is_sensed(i)
            })
        });
        let light = everywhere.as_deref().map(|v| (v, refinement.hints(), rounds.bits.as_slice()));
        let offsets = self.offsets();
        // The radiance cache's values, for samples on surfaces no pixel around them shows (the pixels where
        // the light ends below are resolved even where `plan` holds none).
        let supersampling = frame.aa == Antialiasing::On;
        let cache_values = if global_illumination && supersampling && self.cache.is_some() {
            Some(self.cache_values()?)
        } else {
            None
        };
        let cache_values = cache_values.as_deref();
        let (mut resolved, mut majorities) =
            self.resolve_supersampled(&plan, (&g, targets), light, cache_values, offsets, frame.background)?;
        let mut radiance = transfer::read_buffer::<Vec4>(&device, &targets.composed, pixels)?;
        // Then where the light ends inside a pixel, which only the light as sensed and resolved shows (with
        // the exact light only: the samples' shadow rays place the end, `supersample::shadow`).
        if light.is_some() {
            let mut seen = radiance.clone();
            for (&i, r) in plan.pixels.iter().zip(&resolved) {
                seen[i as usize] = *r;
            }
            let mut ends = supersample::light_ends(&g, &seen, &plan.pixels);
            super::sensing::outside(rounds.region, size.width, &mut ends);
            let ends = supersample::plan(&self.host, &self.bvh, &g, &ends);
            let (more, more_majorities) =
                self.resolve_supersampled(&ends, (&g, targets), light, cache_values, offsets, frame.background)?;
            (resolved, majorities) = ([resolved, more].concat(), [majorities, more_majorities].concat());
            plan.append(ends);
        }
        let supersample_time = start_samples.elapsed();
        let image = transfer::read_buffer::<Vec4>(&device, &targets.image, pixels)?;
        // The AOVs of a supersampled pixel: R over its samples on a surface; the G-buffer's of the surface
        // most of them show.
        for ((&i, r), majority) in plan.pixels.iter().zip(&resolved).zip(majorities) {
            let i = i as usize;
            radiance[i] = r.truncate().extend(radiance[i].w);
            if let Some(v) = majority {
                (g.position[i], g.normal[i], g.albedo[i], g.emission[i], g.surface[i]) =
                    (v.position, v.normal, v.albedo, v.emission, v.surface);
            }
        }
        Ok(Post { image, radiance, gbuffer: g, supersampled: plan.pixels, supersample_time })
    }
}
