//! The radiance cache's bounces on the GPU (docs/DESIGN.md §10): every cache entry is a sensor, sensed by
//! the render's own batch runner (strategy, exact estimator, culling) as if it were a pixel of a one-row
//! image, and the solver turns what they measured into the cache the next bounce, and then the camera's
//! sensors, see.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result};
use glam::{Vec3, Vec4};
use rayon::prelude::*;
use serde::Serialize;

use super::batch::{BatchRunner, Sensed, SensedMaps};
use super::{Phase, Progress};
use crate::gbuffer::GBufferData;
use crate::gi::RadianceCache;
use crate::gi::solve::{Next, Solver};
use crate::gi::transport::{self, Transport};
use crate::gpu_scene::GpuCache;
use crate::params::Bounces;
use crate::passes::sensor_maps::{Background, CacheRead, CkParams};
use crate::scene::ImageSize;
use crate::sensors::weights;
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
    /// rd of the sensors of the bounces after the first, where they are sensed.
    pub sensor_size: u32,
    /// How the bounces after the first were computed.
    pub later: LaterBounces,
    /// Wall time of the first bounce (the direct light at every entry, zoom views and all) and of the
    /// others (its maps only), for `RenderTimes`.
    #[serde(skip)]
    pub seconds: (f64, f64),
}

/// How the radiance cache's bounces after the first were computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LaterBounces {
    /// Sparse products with the transport's rows, read from the first bounce's maps: its weights and bytes.
    Transport { nonzeros: u64, bytes: u64 },
    /// Sensed again, every entry at every bounce: the rows would have needed more than `budget` bytes.
    Sensed { budget: u64 },
}

impl Default for LaterBounces {
    fn default() -> Self {
        Self::Sensed { budget: 0 }
    }
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

/// R at every point of `g` from one sensing pass of `runner` with `ck`; with [`CacheRead::Entries`], `rows`
/// receives each batch's pixels and texel lists.
fn sense(
    runner: &mut BatchRunner,
    g: &GBufferData,
    ck: CkParams,
    progress: &dyn Progress,
    rows: &mut dyn FnMut(&[u32], &[u32]),
) -> Result<Vec<Vec3>> {
    let n = g.position.len();
    let all: Vec<u32> = (0..n as u32).collect();
    let mut r = vec![Vec3::ZERO; n];
    let mut deliver = |b: &Sensed<'_>| {
        b.pixels.iter().zip(b.results).for_each(|(&i, f)| r[i as usize] = f.r.truncate());
        if !b.texels.is_empty() {
            rows(b.pixels, b.texels);
        }
        progress.done(b.pixels.len() as u64);
    };
    runner.sense_or_stop(g, &all, ck, &mut deliver, &|| progress.cancelled())?;
    runner.drain(&mut deliver)?;
    Ok(r)
}

/// The transport's rows as the first bounce's sensors deliver them, within a budget of host memory.
struct Rows {
    rows: Vec<Vec<(u32, f32)>>,
    /// Each main-layer texel's projected solid angle over π.
    weights: Vec<f32>,
    bytes: u64,
    budget: u64,
    over: bool,
}

impl Rows {
    fn new(entries: usize, runner: &BatchRunner, budget: u64) -> Self {
        let weights = weights::sensor_weights(runner.layout().kind, runner.sensor_size());
        Self {
            rows: vec![Vec::new(); entries],
            weights: weights.iter().map(|w| (w / std::f64::consts::PI) as f32).collect(),
            bytes: 0,
            budget,
            over: false,
        }
    }

    /// A batch's sensors (`pixels`) and their texel lists: the entries' rows (the spread points' sensors
    /// have none).
    fn take(&mut self, pixels: &[u32], texels: &[u32]) {
        if self.over {
            return;
        }
        let per_sensor = self.weights.len();
        let (weights, entries) = (&self.weights, self.rows.len());
        let rows: Vec<(u32, Vec<(u32, f32)>)> = (pixels.par_iter().zip(texels.par_chunks_exact(per_sensor)))
            .filter(|(i, _)| (**i as usize) < entries)
            .map_init(Vec::new, |scratch, (&i, t)| (i, transport::row(t, weights, scratch)))
            .collect();
        for (i, row) in rows {
            self.bytes += 8 * row.len() as u64 + 4;
            self.rows[i as usize] = row;
        }
        if self.bytes > self.budget {
            self.over = true;
            self.rows = Vec::new();
        }
    }
}

/// Senses the cache's bounces and leaves the result in `gpu.values`; `background`: what rays leaving the
/// scene see.
///
/// Bounce 1's R at an entry is its direct light (emitters only, the background black: the only pass with
/// zoom views and the emitter pass) and what it sees of the background. Its maps are drawn with
/// [`CacheRead::Entries`], so their main layers, which would hold nothing, say which entry each texel sees:
/// the transport's rows (`gi::transport`). Bounce k adds what the entries see of the light bounce k − 1 added
/// to the cache, `Δ_{k−1}`: transport is linear, so `R_k = R_{k−1} + T·Δ_{k−1}`, a sparse product. Where the
/// rows would exceed `transport_budget` bytes, each later bounce senses the entries again over the cache of
/// `Δ_{k−1}` instead (the maps then hold each bounce's addition in half floats to its own precision, not the
/// cache's sum, whose rounding would drown the small late additions the tail is measured from).
pub(super) fn solve(
    device: &Arc<Device>,
    runners: Runners<'_>,
    (cache, gpu): (&RadianceCache, &GpuCache),
    (bounces, background, transport_budget): (Bounces, Background, u64),
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
    // The first bounce: the direct light and the transport's rows, and what the entries see of the
    // background (its own pass).
    let sky_pass = if background.is_black() { 0 } else { n };
    progress.queued((first.len() + sky_pass) as u64);
    let mut rows = Rows::new(n, runners.first, transport_budget);
    let direct = CkParams { epsilon: 0.0, background: Background::BLACK, cache: CacheRead::Entries };
    let sensed = sense(runners.first, &first_g, direct, progress, &mut |i, t| rows.take(i, t))?;
    let mut r = sensed[..n].to_vec();
    let mut spread = vec![(Vec3::ZERO, 0u32); n];
    for (&(_, i), s) in first[n..].iter().zip(&sensed[n..]) {
        spread[i] = (spread[i].0 + *s, spread[i].1 + 1);
    }
    r.iter_mut().zip(spread).filter(|(_, (_, count))| *count > 0).for_each(|(r, (sum, count))| *r = sum / count as f32);
    let transport = (!rows.over).then(|| Transport::from_rows(&rows.rows));
    drop(rows);
    let first_seconds = start.elapsed().as_secs_f64();
    if !background.is_black() {
        let ck = CkParams { epsilon: 0.0, background, cache: CacheRead::Off };
        let sky = sense(runners.later, &g, ck, progress, &mut |_, _| ())?;
        r.iter_mut().zip(sky).for_each(|(r, s)| *r += s);
    }
    // What the last bounce added, as the values buffer holds it (its surface sides' means after it).
    let mut added_values: Vec<Vec3> = Vec::new();
    loop {
        let bounce = solver.bounces() + 1;
        if bounce > 1 {
            let added = match &transport {
                Some(t) => t.apply(&added_values),
                None => {
                    progress.queued(n as u64);
                    let ck = CkParams { epsilon: 0.0, background: Background::BLACK, cache: CacheRead::Values };
                    sense(runners.later, &g, ck, progress, &mut |_, _| ())?
                }
            };
            r.iter_mut().zip(added).for_each(|(r, a)| *r += a);
        }
        let next = solver.step(&cache.entries, &cache.albedo, &r);
        // Between bounces what this one added (the next transports it); at the end the estimate.
        let values =
            if next == Next::Done { cache.gpu_values(&solver.values()) } else { cache.gpu_values(solver.added()) };
        if transport.is_none() || next == Next::Done {
            transfer::write_buffer(device, &gpu.values, &values).context("update the radiance cache")?;
        }
        added_values = values.iter().map(|v| v.truncate()).collect();
        let sensors = if transport.is_some() && bounce > 1 { 0 } else { n as u64 };
        progress.bounce(&BounceDone { bounce, sensors, change: solver.last_change });
        if next == Next::Done {
            break;
        }
    }
    let later = match &transport {
        Some(t) => LaterBounces::Transport { nonzeros: t.nonzeros() as u64, bytes: t.bytes() },
        None => LaterBounces::Sensed { budget: transport_budget },
    };
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
        later,
        last_change: solver.last_change,
        ratio: solver.ratio(),
        tail_share: solver.tail_share(),
        seconds: (first_seconds, start.elapsed().as_secs_f64() - first_seconds),
    })
}
