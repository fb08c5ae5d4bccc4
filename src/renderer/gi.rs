//! The radiance cache's bounces on the GPU (docs/DESIGN.md §10): every cache entry is a sensor, sensed by
//! the render's own batch runner (strategy, exact estimator, culling) as if it were a pixel of a one-row
//! image, and the solver turns what they measured into the cache the next bounce, and then the camera's
//! sensors, see.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result};
use glam::{Vec3, Vec4};
use serde::Serialize;

use super::batch::{BatchRunner, SensedMaps};
use super::{Phase, Progress};
use crate::gbuffer::GBufferData;
use crate::gi::RadianceCache;
use crate::gi::solve::{Next, Solver};
use crate::gpu_scene::GpuCache;
use crate::gpu_types::GpuSensorResult;
use crate::params::Bounces;
use crate::passes::sensor_maps::{Background, CkParams};
use crate::scene::ImageSize;
use crate::vk::{Device, transfer};

/// A bounce done: for progress displays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BounceDone {
    /// 1-based.
    pub bounce: u32,
    pub sensors: u64,
    /// How much the cache's estimate moved, relative (luminance × area); `None` after the first.
    pub change: Option<f64>,
}

/// What the bounces did, for the statistics.
#[derive(Clone, Debug, Default, Serialize)]
pub struct GiStats {
    /// Bounces sensed.
    pub bounces: u32,
    /// Cache entries (sensors per bounce), keys in its table, and its bytes on the GPU.
    pub entries: u64,
    /// Pieces halved because their direct light varies over them (`gi::entries::MAX_LIGHT_LEVELS`), and the
    /// entry pairs whose direct light is still measured at points spread over them.
    pub light_splits: u64,
    pub spread_pairs: u64,
    pub keys: u64,
    pub cache_bytes: u64,
    /// Cells along the scene's longest side, and their size.
    pub resolution: u32,
    pub cell: f32,
    /// The last bounce's relative change of the cache (auto: of its extrapolated estimate).
    pub last_change: Option<f64>,
    /// auto: the ratio λ by which bounces shrink, and the share of the cache's light its tail adds.
    pub ratio: Option<f64>,
    pub tail_share: f64,
    /// rd of the sensors of the bounces after the first.
    pub sensor_size: u32,
    /// Wall time of the first bounce (the direct light at every entry, zoom views and all) and of the
    /// others (its maps only), for `RenderTimes`.
    #[serde(skip)]
    pub seconds: (f64, f64),
}

/// Points on the cache's pieces as a one-row G-buffer: the batch runner places a sensor at each
/// `(point, entry)`, facing that entry's side.
fn points_as_gbuffer(cache: &RadianceCache, points: &[(Vec3, usize)]) -> GBufferData {
    let n = points.len();
    let (mut position, mut normal) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for &(p, i) in points {
        let e = &cache.entries[i];
        position.push(p.extend(1.0));
        normal.push(e.normal.extend(e.front as u32 as f32));
    }
    GBufferData {
        size: ImageSize { width: n as u32, height: 1 },
        position,
        normal,
        albedo: points.iter().map(|&(_, i)| cache.albedo[i].extend(1.0)).collect(),
        emission: vec![Vec4::ZERO; n],
        surface: points.iter().map(|&(_, i)| cache.entries[i].surface).collect(),
    }
}

/// The first bounce's sensors: every entry's point, then the points spread over each piece whose direct
/// light varies over it (both sides), whose mean is that entry's direct light.
fn first_points(cache: &RadianceCache) -> Vec<(Vec3, usize)> {
    let mut points: Vec<(Vec3, usize)> = cache.entries.iter().enumerate().map(|(i, e)| (e.point, i)).collect();
    for (pair, spread) in &cache.spread {
        for entry in [2 * *pair as usize, 2 * *pair as usize + 1] {
            points.extend(spread.iter().map(|&p| (p, entry)));
        }
    }
    points
}

/// The runners the bounces sense with: the render's own for the first (direct light, through the exact
/// estimator's zoom views at the render's rd), and the cache's for the others, which measure only what the
/// maps see on surfaces and the background, with smaller maps.
pub(super) struct Runners<'a> {
    pub first: &'a mut BatchRunner,
    pub later: &'a mut BatchRunner,
}

/// R at every entry from one sensing pass of `runner` with `ck`.
fn sense(runner: &mut BatchRunner, g: &GBufferData, ck: CkParams, progress: &dyn Progress) -> Result<Vec<Vec3>> {
    let n = g.position.len();
    let all: Vec<u32> = (0..n as u32).collect();
    let mut r = vec![Vec3::ZERO; n];
    let mut deliver = |p: &[u32], found: &[GpuSensorResult]| {
        p.iter().zip(found).for_each(|(&i, f)| r[i as usize] = f.r.truncate());
        progress.done(p.len() as u64);
    };
    runner.sense_or_stop(g, &all, ck, &mut deliver, &|| progress.cancelled())?;
    runner.drain(&mut deliver)?;
    Ok(r)
}

/// Senses the cache's bounces and leaves the result in `gpu.values`; `background`: what rays leaving the
/// scene see.
///
/// Bounce 1's R at an entry is its direct light (emitters only, the background black: the only pass with
/// zoom views and the emitter pass) and what it sees of the background. Bounce k adds what its maps see of
/// the light bounce k − 1 added to the cache, `Δ_{k−1}`: transport is linear, so `R_k = R_{k−1} + T·Δ_{k−1}`.
/// The maps then hold each bounce's addition in half floats to its own precision, not the cache's sum (whose
/// rounding, at 1e-3 of ρ = 0.9's sum, would drown the small late additions the tail is measured from).
pub(super) fn solve(
    device: &Arc<Device>,
    runners: Runners<'_>,
    (cache, gpu): (&RadianceCache, &GpuCache),
    (bounces, background): (Bounces, Background),
    progress: &dyn Progress,
) -> Result<GiStats> {
    let start = Instant::now();
    progress.phase(Phase::Bounces);
    let n = cache.entries.len();
    let first = first_points(cache);
    let (g, first_g) = (points_as_gbuffer(cache, &first[..n]), points_as_gbuffer(cache, &first));
    // The reductions write R at each sensor's pixel: the first pass has the most.
    let maps = SensedMaps::new(device, first_g.size)?;
    runners.first.bind(&maps)?;
    runners.later.bind(&maps)?;
    let mut solver = Solver::new(bounces, crate::gi::solve::DEFAULT_TOLERANCE, n);
    // The first bounce: the direct light, and what the entries see of the background (its own pass).
    let sky_pass = if background.is_black() { 0 } else { n };
    progress.queued((first.len() + sky_pass) as u64);
    let direct = CkParams { epsilon: 0.0, background: Background::BLACK, cache: false };
    let sensed = sense(runners.first, &first_g, direct, progress)?;
    let mut r = sensed[..n].to_vec();
    let mut spread = vec![(Vec3::ZERO, 0u32); n];
    for (&(_, i), s) in first[n..].iter().zip(&sensed[n..]) {
        spread[i] = (spread[i].0 + *s, spread[i].1 + 1);
    }
    r.iter_mut().zip(spread).filter(|(_, (_, count))| *count > 0).for_each(|(r, (sum, count))| *r = sum / count as f32);
    let first_seconds = start.elapsed().as_secs_f64();
    if !background.is_black() {
        let sky = sense(runners.later, &g, CkParams { epsilon: 0.0, background, cache: false }, progress)?;
        r.iter_mut().zip(sky).for_each(|(r, s)| *r += s);
    }
    loop {
        let bounce = solver.bounces() + 1;
        if bounce > 1 {
            progress.queued(n as u64);
            let added = sense(
                runners.later,
                &g,
                CkParams { epsilon: 0.0, background: Background::BLACK, cache: true },
                progress,
            )?;
            r.iter_mut().zip(added).for_each(|(r, a)| *r += a);
        }
        let next = solver.step(&cache.entries, &cache.albedo, &r);
        // Between bounces what this one added (the next transports it); at the end the estimate.
        let values = if next == Next::Done { solver.values() } else { solver.added().to_vec() };
        transfer::write_buffer(device, &gpu.values, &cache.gpu_values(&values)).context("update the radiance cache")?;
        progress.bounce(&BounceDone { bounce, sensors: n as u64, change: solver.last_change });
        if next == Next::Done {
            break;
        }
    }
    Ok(GiStats {
        bounces: solver.bounces(),
        entries: n as u64,
        light_splits: cache.light_splits as u64,
        spread_pairs: cache.spread.len() as u64,
        keys: cache.keys as u64,
        cache_bytes: cache.bytes(),
        resolution: cache.resolution,
        cell: cache.grid.cell,
        sensor_size: runners.later.sensor_size(),
        last_change: solver.last_change,
        ratio: solver.ratio(),
        tail_share: solver.tail_share(),
        seconds: (first_seconds, start.elapsed().as_secs_f64() - first_seconds),
    })
}
