//! A render's sensing (paper §III-G): sensors on the grid, then rounds of refinement until no quad asks for
//! more, each round's sensors in batches on the GPU. The host keeps R only where it sensed: that is all the
//! refinement reads. Before the first round, the light hints (which points on the lights each pixel sees)
//! and which pixels take sub-pixel samples (docs/DESIGN.md §11).

use std::cell::RefCell;
use std::time::{Duration, Instant};

use anyhow::Result;
use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::batch::Sensed;
use super::fine::Slits;
use super::gaps::Gaps;
use super::preview::{PreviewLight, preview};
use super::targets::Targets;
use super::{Progress, Renderer, RoundDone, Snapshot};
use crate::gbuffer::GBufferData;
use crate::gpu_types::MAX_GROUPS;
use crate::params::{Antialiasing, FrameParams, Region};
use crate::sensors::hints;
use crate::sensors::refine::{Refinement, Visibility};
use crate::supersample;
use crate::vk::transfer;

/// What the post passes need of the rounds (R itself is in the targets' maps).
pub(super) struct Rounds {
    /// With the exact estimator: each light group's visibility at every pixel sensed (−1 elsewhere).
    pub(super) visibility: Vec<Visibility>,
    /// Where sensors went, and the quads interpolated.
    pub(super) refinement: Refinement,
    /// Whether each light group's unoccluded light is computed per pixel and only the visibilities and the
    /// rest of R interpolated (`interpolate_exact.comp`).
    pub(super) exact_interpolation: bool,
    /// Each light group's hint bits.
    pub(super) bits: Vec<u64>,
    /// The pixels that take sub-pixel samples, and what their samples see.
    pub(super) plan: supersample::Plan,
    /// The pixels that must be right: the frame's region grown by [`REGION_MARGIN`] (`None`: all).
    pub(super) region: Option<Region>,
    /// Sensors, and bytes read back, per round.
    pub(super) per_round: Vec<u64>,
    pub(super) readback_per_round: Vec<u64>,
    /// Sensors sensed again at the finer rd where a slit fell between the texels (`fine`).
    pub(super) fine_sensors: u64,
    /// The host's time on the light hints and the refinement's steps; on the supersampling plan.
    pub(super) refine_time: Duration,
    pub(super) supersample_time: Duration,
}

/// How far beyond a frame's region (a tile) its pixels are made right, besides the filters' radius: a
/// supersampled pixel's samples take R from donors a pixel away, whose R the filter made; where the light
/// ends inside a pixel is judged from its neighbours as resolved, themselves from their donors: three
/// pixels in all (4 tiles of the Cornell box at 256² sense 1.26× the single render's sensors with 8,
/// docs/BENCHMARKS.md "Many processes").
pub const REGION_MARGIN: u32 = 3;

impl Renderer {
    /// Senses the image of G-buffer `g` into `targets`' maps, round by round; previews and progress through
    /// `progress`, which may stop it between batches. `sky`: the sky each pixel shows, under a sky map.
    pub(super) fn sense_rounds(
        &mut self,
        g: &GBufferData,
        targets: &Targets,
        frame: &FrameParams,
        sky: Option<&[Vec3]>,
        progress: &dyn Progress,
    ) -> Result<Rounds> {
        let pixels = g.size.width as usize * g.size.height as usize;
        let ck = self.ck(frame);
        let (refinement, mut pending) = Refinement::start(g, frame.tile, frame.dradiance);
        let margin = REGION_MARGIN + frame.filter_radius.max(frame.indirect_filter_radius);
        let region = frame.region.map(|r| r.grown(margin, (g.size.width, g.size.height)));
        let refinement = refinement.within(region);
        let t = Instant::now();
        let (bias, near) = self.offsets();
        let masks = self.light_points.as_ref().map(|points| hints::hints(&self.bvh, points, g, bias, near));
        if let Some(masks) = &masks {
            transfer::write_buffer(&self.device, &targets.light_masks, masks)?;
        }
        let hint_time = t.elapsed();
        // Which pixels take sub-pixel samples, and what the samples see (docs/DESIGN.md §11).
        let t = Instant::now();
        let bits = self.light_points.as_ref().map(|_| hints::group_bits(&self.scene.lights)).unwrap_or_default();
        let plan = match frame.aa {
            Antialiasing::On => {
                let mut flags = supersample::detect(&self.host, g, masks.as_deref().unwrap_or(&[]), &bits);
                if let (Some(points), Some(masks)) = (&self.light_points, &masks) {
                    let light = (points.as_slice(), (bias, near));
                    let between = supersample::light_between_centres(&self.host, &self.bvh, g, light, (masks, &bits));
                    flags.iter_mut().zip(between).for_each(|(f, between)| f.light |= between);
                }
                outside(region, g.size.width, &mut flags);
                supersample::plan(&self.host, &self.bvh, g, &flags)
            }
            Antialiasing::Off => supersample::Plan::default(),
        };
        let supersample_time = t.elapsed();
        // A light seen through a gap: where a sensor saw part of a group, shadow rays measure it (`gaps`;
        // the exact estimator's visibilities, and the light hints).
        let exact = self.estimate.groups > 0;
        let gaps = (self.shadow_points.as_ref()).filter(|_| exact && masks.is_some()).map(|points| Gaps {
            bvh: &self.bvh,
            points,
            lights: &self.scene.lights,
            bits: &bits,
            offsets: (bias, near),
        });
        // Per pixel, what the shadow rays moved its last sensor's R by.
        let mut changes = vec![Vec3::ZERO; pixels];
        let slits = RefCell::new(Slits::new(g.size));
        let mut refinement = match masks {
            Some(masks) => refinement.with_hints(masks),
            None => refinement,
        };
        let mut r = vec![Vec4::ZERO; pixels];
        let mut visibility: Vec<Visibility> = if exact { vec![[-1.0; MAX_GROUPS]; pixels] } else { Vec::new() };
        let exact_interpolation = self.estimate.exact_interpolation;
        let mut rest = if exact_interpolation { vec![Vec4::ZERO; pixels] } else { Vec::new() };
        let (mut per_round, mut readback_per_round) = (Vec::new(), Vec::new());
        let mut refine_time = hint_time;
        loop {
            if !pending.is_empty() {
                progress.queued(pending.len() as u64);
                let read_before = self.runner.times.readback_bytes;
                let hint_masks = refinement.hints();
                let mut deliver = |b: &Sensed<'_>| {
                    let measured: Vec<Option<(Visibility, Vec3)>> = (b.pixels.par_iter().zip(b.results))
                        .map(|(&i, f)| {
                            let gaps = gaps.as_ref()?;
                            let (i, mut v) = (i as usize, f.visibility);
                            let at = (g.position[i].truncate(), g.normal[i].truncate());
                            let change = gaps.measure(at, hint_masks[i], &mut v);
                            (v != f.visibility).then_some((v, change))
                        })
                        .collect();
                    for ((&i, f), measured) in b.pixels.iter().zip(b.results).zip(measured) {
                        r[i as usize] = f.r;
                        if exact {
                            visibility[i as usize] = f.visibility;
                        }
                        changes[i as usize] = Vec3::ZERO;
                        if let Some((v, change)) = measured {
                            visibility[i as usize] = v;
                            r[i as usize] += change.extend(0.0);
                            changes[i as usize] = change;
                        }
                        slits.borrow_mut().record(i, f.rest.w);
                        if exact_interpolation {
                            rest[i as usize] = f.rest;
                        }
                    }
                    progress.done(b.pixels.len() as u64);
                };
                self.runner.sense_or_stop(g, &pending, ck, &mut deliver, &|| progress.cancelled())?;
                self.runner.drain(&mut deliver)?;
                // Where a slit fell between the texels, finer sensors (`fine`), until none is near another.
                if let Some(fine) = &mut self.fine {
                    loop {
                        let again = slits.borrow_mut().take();
                        if again.is_empty() {
                            break;
                        }
                        progress.queued(again.len() as u64);
                        fine.sense_or_stop(g, &again, ck, &mut deliver, &|| progress.cancelled())?;
                        fine.drain(&mut deliver)?;
                    }
                }
                per_round.push(pending.len() as u64);
                readback_per_round.push(self.runner.times.readback_bytes - read_before);
                let round = per_round.len() as u32;
                if progress.wants_snapshot(round) {
                    let light = exact_interpolation.then(|| PreviewLight {
                        visibility: &visibility,
                        rest: &rest,
                        lights: &self.scene.lights,
                        bias,
                    });
                    let image = preview(g, &r, &refinement, (frame.background, sky), light);
                    progress.snapshot(&Snapshot { round, size: g.size, image });
                }
            }
            if refinement.is_finished() {
                break;
            }
            let t = Instant::now();
            pending = refinement.step(&r, &visibility, &rest);
            refine_time += t.elapsed();
            progress.round(&RoundDone {
                round: per_round.len() as u32,
                sensors: per_round.last().copied().unwrap_or(0),
                resolved_pixels: pixels as u64 - refinement.unresolved_pixels(),
                pixels: pixels as u64,
            });
        }
        // The sensed R the shadow rays moved, in the map the post passes read.
        if changes.iter().any(|&c| c != Vec3::ZERO) {
            let map = &targets.sensed.radiance;
            let mut sensed = transfer::read_buffer::<Vec4>(&self.device, map, pixels)?;
            sensed.iter_mut().zip(&changes).for_each(|(r, change)| *r += change.extend(0.0));
            transfer::write_buffer(&self.device, map, &sensed)?;
        }
        let fine_sensors = slits.into_inner().count();
        Ok(Rounds {
            fine_sensors,
            region,
            visibility,
            refinement,
            exact_interpolation,
            bits,
            plan,
            per_round,
            readback_per_round,
            refine_time,
            supersample_time,
        })
    }
}

/// Clears the supersampling's flags of the pixels outside `region` (an image `width` wide): only the
/// region's pixels must be right.
pub(super) fn outside(region: Option<Region>, width: u32, flags: &mut [supersample::Flags]) {
    if let Some(r) = region {
        let inside = |i: usize| r.contains(i as u32 % width, i as u32 / width);
        flags.iter_mut().enumerate().filter(|(i, _)| !inside(*i)).for_each(|(_, f)| *f = supersample::Flags::default());
    }
}
