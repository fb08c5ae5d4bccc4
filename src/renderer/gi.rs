//! The radiance cache's bounces on the GPU (docs/DESIGN.md §10): every cache entry is a sensor, sensed by
//! the render's own batch runner (strategy, exact estimator, culling) as if it were a pixel of a one-row
//! image, and the solver turns what they measured into the cache the next bounce, and then the camera's
//! sensors, see.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result};
use glam::{Vec3, Vec4};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::batch::{BatchRunner, Sensed, SensedMaps};
use super::{Phase, Progress};
use crate::gbuffer::GBufferData;
use crate::gi::RadianceCache;
use crate::gi::entries::SAMPLES_PER_PIECE;
use crate::gi::piece_mean::Surroundings;
use crate::gi::reach::Reach;
use crate::gi::solve::{Next, Solver};
use crate::gi::transport::{self, Transport};
use crate::gpu_scene::GpuCache;
use crate::params::{Bounces, FrameParams};
use crate::passes::sensor_maps::{Background, CacheRead, CkParams};
use crate::scene::ImageSize;
use crate::sensors::hints::{self, LightPoint};
use crate::sensors::weights;
use crate::supersample::ShadowPoints;
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

/// A level of the radiance cache's walk begins (`gi::reach`): for progress displays, which know then
/// how much of the cache, at most, is still to sense.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CacheLevel {
    /// 1-based.
    pub level: u32,
    /// The level's sensors, the entries reached with them, and all the cache's (what the walk may reach).
    pub sensors: u64,
    pub reached: u64,
    pub entries: u64,
}

/// What the bounces did, for the statistics.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct GiStats {
    /// Bounces sensed.
    pub bounces: u32,
    /// Cache entries, keys in its table, and its bytes on the GPU.
    pub entries: u64,
    /// The entries light reaches (`gi::reach`), which alone are sensed, and the levels of the walk that
    /// found them.
    pub reached: u64,
    pub levels: u32,
    /// Sensors at points spread over the reached pieces whose direct light varies over them.
    pub spread_sensors: u64,
    /// The triangles the walk's sensors drew, all their views (where the scene is drawn from its clusters).
    pub drawn_triangles: Option<u64>,
    /// Pieces halved because their direct light varies over them (`gi::entries::MAX_LIGHT_LEVELS`), and the
    /// entry pairs whose direct light is still measured at points spread over them.
    pub light_splits: u64,
    pub spread_pairs: u64,
    /// Entries moved to their piece's mean light where it differs from their point's (`gi::piece_mean`).
    #[serde(default)]
    pub piece_means: u64,
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
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

/// Every entry's own point, entry i at pixel i: an entry's sensor is the same (turned alike) in every pass.
fn entry_points(cache: &RadianceCache) -> Vec<(Vec3, usize)> {
    cache.entries.iter().enumerate().map(|(i, e)| (e.point, i)).collect()
}

/// The entries of the pieces whose direct light varies over them, on the sides `reach` reached: the mean of
/// the direct light at their piece's spread points is theirs.
fn spread_entries(cache: &RadianceCache, reach: &Reach) -> Vec<usize> {
    let sides = |&pair: &u32| [2 * pair as usize, 2 * pair as usize + 1];
    cache.spread.iter().flat_map(sides).filter(|&e| reach.is_reached(e)).collect()
}

/// The points spread over the pieces of `entries`, each with its entry: eight consecutive points per entry.
fn spread_points(cache: &RadianceCache, entries: &[usize]) -> Vec<(Vec3, usize)> {
    entries.iter().flat_map(|&e| cache.points[e / 2].iter().map(move |&(p, _)| (p, e))).collect()
}

/// Points on each light group at which an entry whose light hints see only part of the group casts shadow
/// rays. The hints' 16 points a group quantise a share to sixteenths, and light through a gap narrower than
/// their spacing was missed: the door ajar's room, lit through a gap, took 8 % too little direct light
/// (docs/ACCURACY.md). With 256 its floor is within 2 %, as with 1 024.
pub const SHADOW_POINTS: usize = 256;

/// The direct light at a point `p` of normal `n` as shadow rays to points on the lights weigh each light
/// group's unoccluded irradiance in closed form: the light hints' points (`sensors::hints`), and where
/// these see part of a group, [`SHADOW_POINTS`] of it. What the entries and the spread points take.
pub(super) type DirectByRays<'a> = &'a (dyn Fn(Vec3, Vec3) -> Vec3 + Sync);

/// An uneven piece's direct light as the mean over the points spread over it: its sensor's R, moved by how
/// much the shadow rays' estimate of the mean differs from theirs at the sensor's own point (a control
/// variate: where the rays see what the sensor saw, the sensor's measure is kept). Eight sensors a side
/// cost more than all the other entries on a lamp-lit room; 8 × 64 rays do not.
fn spread_by_rays(cache: &RadianceCache, spread: &[usize], rays: DirectByRays<'_>, r: &mut [Vec3]) {
    let moves: Vec<(usize, Vec3)> = spread
        .par_iter()
        .map(|&i| {
            let entry = &cache.entries[i];
            // Each point facing its own triangle's way: a curved piece's mean normal is not its points'.
            let side = if entry.front { 1.0 } else { -1.0 };
            let at = cache.points[i / 2];
            let mean = at.iter().map(|&(p, n)| rays(p, n * side)).sum::<Vec3>() / at.len() as f32;
            (i, mean - rays(entry.point, entry.normal))
        })
        .collect();
    for (i, m) in moves {
        r[i] = (r[i] + m).max(Vec3::ZERO);
    }
}

/// The runners the bounces sense with: the render's own for the first (direct light, through the exact
/// estimator's zoom views at the render's rd), and the cache's for the others, which measure only what the
/// maps see on surfaces and the background, with smaller maps.
pub(super) struct Runners<'a> {
    pub first: &'a mut BatchRunner,
    pub later: &'a mut BatchRunner,
}

/// R at `pixels` of `g` (every point where `None`) from one sensing pass of `runner` with `ck`, per pixel of
/// `g` (zero where not sensed); with [`CacheRead::Entries`], `rows` receives each batch's pixels and texel
/// lists.
fn sense(
    runner: &mut BatchRunner,
    (g, pixels): (&GBufferData, Option<&[u32]>),
    ck: CkParams,
    progress: &dyn Progress,
    rows: &mut dyn FnMut(&[u32], &[u32]),
) -> Result<Vec<Vec3>> {
    let n = g.position.len();
    let all: Vec<u32>;
    let pixels = match pixels {
        Some(p) => p,
        None => {
            all = (0..n as u32).collect();
            &all
        }
    };
    progress.queued(pixels.len() as u64);
    let mut r = vec![Vec3::ZERO; n];
    let mut deliver = |b: &Sensed<'_>| {
        b.pixels.iter().zip(b.results).for_each(|(&i, f)| r[i as usize] = f.r.truncate());
        if !b.texels.is_empty() {
            rows(b.pixels, b.texels);
        }
        progress.done(b.pixels.len() as u64);
    };
    runner.sense_or_stop(g, pixels, ck, &mut deliver, &|| progress.cancelled())?;
    runner.drain(&mut deliver)?;
    Ok(r)
}

/// The transport's rows as the first bounce's sensors deliver them, within a budget of host memory, and the
/// values each level's sensors saw (the walk's next level).
struct Rows {
    rows: Vec<Vec<(u32, f32)>>,
    /// Each entry's weight of texels that see no surface (over π), kept whatever the budget.
    sky: Vec<f32>,
    /// The values the sensors since the last [`Rows::seen`] saw.
    seen: Vec<u32>,
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
            sky: vec![0.0; entries],
            seen: Vec::new(),
            weights: weights.iter().map(|w| (w / std::f64::consts::PI) as f32).collect(),
            bytes: 0,
            budget,
            over: false,
        }
    }

    /// A batch's sensors (`entries`: pixel i senses entry i) and their texel lists: those entries' rows.
    fn take(&mut self, entries: &[u32], texels: &[u32]) {
        let per_sensor = self.weights.len();
        let weights = &self.weights;
        let rows: Vec<(u32, (transport::Row, f32))> = (entries.par_iter().zip(texels.par_chunks_exact(per_sensor)))
            .map_init(Vec::new, |scratch, (&i, t)| (i, transport::row(t, weights, scratch)))
            .collect();
        for (entry, (row, sky)) in rows {
            self.sky[entry as usize] = sky;
            self.seen.extend(row.iter().map(|&(c, _)| c));
            if !self.over {
                self.bytes += 8 * row.len() as u64 + 4;
                self.rows[entry as usize] = row;
            }
        }
        if !self.over && self.bytes > self.budget {
            self.over = true;
            self.rows = Vec::new();
        }
    }

    /// The values seen since the last call.
    fn seen(&mut self) -> impl Iterator<Item = u32> {
        std::mem::take(&mut self.seen).into_iter()
    }
}

/// Senses the cache's bounces and leaves the result in `gpu.values`; `background`: what rays leaving the
/// scene see.
///
/// Bounce 1's R at an entry is its direct light (emitters only, the background black: by shadow rays, or
/// the only pass with zoom views and the emitter pass) and what it sees of the background (a constant's
/// from the rows' sky weights, a sky map's by a pass of its own). Its maps are drawn with
/// [`CacheRead::Entries`], so their main layers, which would hold nothing, say which entry each texel sees:
/// the transport's rows (`gi::transport`). Bounce k adds what the entries see of the light bounce k − 1 added
/// to the cache, `Δ_{k−1}`: transport is linear, so `R_k = R_{k−1} + T·Δ_{k−1}`, a sparse product. Where the
/// rows would exceed `transport_budget` bytes, each later bounce senses the entries again over the cache of
/// `Δ_{k−1}` instead (the maps then hold each bounce's addition in half floats to its own precision, not the
/// cache's sum, whose rounding would drown the small late additions the tail is measured from).
pub(super) fn solve(
    device: &Arc<Device>,
    runners: Runners<'_>,
    (cache, gpu, seeds): (&RadianceCache, &GpuCache, Vec<u32>),
    (bounces, background, transport_budget): (Bounces, Background, u64),
    (rays, around): (Option<DirectByRays<'_>>, Option<&Surroundings<'_>>),
    progress: &dyn Progress,
) -> Result<GiStats> {
    let start = Instant::now();
    progress.phase(Phase::Bounces);
    let n = cache.entries.len();
    // The reductions write R at each sensor's pixel: an entry's is its index, a spread point's its place
    // among them.
    let most = n.max(cache.spread.len() * 2 * SAMPLES_PER_PIECE).max(1);
    let g = points_as_gbuffer(cache, &entry_points(cache));
    let maps = SensedMaps::new(device, ImageSize { width: most as u32, height: 1 })?;
    runners.first.bind(&maps)?;
    runners.later.bind(&maps)?;
    let mut solver = Solver::new(bounces, crate::gi::solve::DEFAULT_TOLERANCE, n);
    // The first bounce, level by level of the walk from the seeds: each level's direct light and rows, whose
    // values not yet reached are the next level. With shadow rays, the direct light is theirs and the rows
    // come from the cache's own smaller maps, without zoom views; else both from the render's sensors.
    let runner = if rays.is_some() { &mut *runners.later } else { &mut *runners.first };
    let mut reach = Reach::new(n, &cache.buried);
    let mut rows = Rows::new(n, runner, transport_budget);
    let mut r = vec![Vec3::ZERO; n];
    let mut level = seeds;
    let mut levels = 0;
    while !level.is_empty() {
        reach.mark(&level);
        levels += 1;
        let (sensors, reached) = (level.len() as u64, reach.count() as u64);
        progress.cache_level(&CacheLevel { level: levels, sensors, reached, entries: n as u64 });
        let direct = CkParams { epsilon: 0.0, background: Background::BLACK, cache: CacheRead::Entries };
        let sensed = sense(runner, (&g, Some(&level)), direct, progress, &mut |p, t| rows.take(p, t))?;
        match rays {
            Some(rays) => {
                let at = |&i: &u32| rays(cache.entries[i as usize].point, cache.entries[i as usize].normal);
                let direct: Vec<Vec3> = level.par_iter().map(at).collect();
                level.iter().zip(direct).for_each(|(&i, d)| r[i as usize] = d);
            }
            None => level.iter().for_each(|&i| r[i as usize] = sensed[i as usize]),
        }
        level = reach.next(rows.seen());
    }
    let drawn_triangles = runner.times.drawn_triangles;
    // Pieces whose direct light varies over them: the mean of the points spread over them.
    let spread_entries = spread_entries(cache, &reach);
    let spread = if rays.is_some() { Vec::new() } else { spread_points(cache, &spread_entries) };
    let spread_sensors = spread.len();
    if let Some(rays) = rays {
        spread_by_rays(cache, &spread_entries, rays, &mut r);
    } else if !spread.is_empty() {
        let direct = CkParams { epsilon: 0.0, background: Background::BLACK, cache: CacheRead::Off };
        let spread_g = points_as_gbuffer(cache, &spread);
        let sensed = sense(runners.first, (&spread_g, None), direct, progress, &mut |_, _| ())?;
        let mut sums = vec![(Vec3::ZERO, 0u32); n];
        for (&(_, i), s) in spread.iter().zip(&sensed) {
            sums[i] = (sums[i].0 + *s, sums[i].1 + 1);
        }
        r.iter_mut().zip(sums).filter(|(_, (_, k))| *k > 0).for_each(|(r, (sum, k))| *r = sum / k as f32);
    }
    let reached = reach.reached();
    // What the entries see of the sky: a constant one is the rows' sky weight times its radiance; a sky
    // map, which varies with the direction, its own pass.
    match background {
        Background::Constant(sky) => r.iter_mut().zip(&rows.sky).for_each(|(r, &w)| *r += sky * w),
        Background::SkyMap => {
            let ck = CkParams { epsilon: 0.0, background, cache: CacheRead::Off };
            let sky = sense(runners.later, (&g, Some(&reached)), ck, progress, &mut |_, _| ())?;
            r.iter_mut().zip(sky).for_each(|(r, s)| *r += s);
        }
    }
    let transport = (!rows.over).then(|| Transport::from_rows(&rows.rows));
    drop(rows);
    let first_seconds = start.elapsed().as_secs_f64();
    // What the last bounce added, as the values buffer holds it (its surface sides' means after it).
    let mut added_values: Vec<Vec3> = Vec::new();
    let mut piece_means = 0;
    loop {
        let bounce = solver.bounces() + 1;
        if bounce > 1 {
            let added = match &transport {
                Some(t) => t.apply(&added_values),
                None => {
                    let ck = CkParams { epsilon: 0.0, background: Background::BLACK, cache: CacheRead::Values };
                    sense(runners.later, (&g, Some(&reached)), ck, progress, &mut |_, _| ())?
                }
            };
            r.iter_mut().zip(added).for_each(|(r, a)| *r += a);
        }
        let next = solver.step(&cache.entries, &cache.albedo, &r);
        // Between bounces what this one added (the next transports it); at the end the estimate.
        let values = match (next, around) {
            (Next::Done, Some(around)) => {
                // What the entries' last R saw: the converged cache (a fixed point, its tail in), or with
                // `--bounces N` the cache before the last bounce (none after the first: R is direct light).
                let values = solver.values();
                let seen: Vec<Vec3> = match bounces {
                    Bounces::Converged => values.clone(),
                    Bounces::Fixed(_) => values.iter().zip(solver.added()).map(|(v, a)| *v - *a).collect(),
                };
                let means = crate::gi::piece_mean::piece_means(cache, (&values, &seen), &reached, around);
                piece_means = means.1;
                cache.gpu_values(&means.0)
            }
            (Next::Done, None) => cache.gpu_values(&solver.values()),
            _ => cache.gpu_values(solver.added()),
        };
        if transport.is_none() || next == Next::Done {
            transfer::write_buffer(device, &gpu.values, &values).context("update the radiance cache")?;
        }
        added_values = values.iter().map(|v| v.truncate()).collect();
        let sensors = match (bounce, &transport) {
            (1, _) => (reached.len() + spread_sensors) as u64,
            (_, Some(_)) => 0,
            (_, None) => reached.len() as u64,
        };
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
        reached: reached.len() as u64,
        levels,
        spread_sensors: spread_sensors as u64,
        drawn_triangles,
        light_splits: cache.light_splits as u64,
        spread_pairs: cache.spread.len() as u64,
        piece_means: piece_means as u64,
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

impl super::Renderer {
    /// Takes `values` (a cache file's: one per entry, then the surface sides' fallbacks) as the radiance
    /// cache's solution for `frame`'s light, solved as `stats` says, in place of solving it: every later
    /// render with that light reads it ([`Renderer::keep_cache`]). An error where the renderer has no cache
    /// or `values` is not the size of its cache.
    pub fn use_cache(&mut self, values: &[Vec4], frame: &FrameParams, stats: GiStats) -> Result<()> {
        let cache = self.cache().context(
            "this render has no radiance cache to read (it computes no global illumination: --bounces 0 or --epsilon)",
        )?;
        anyhow::ensure!(
            values.len() == cache.values_len(),
            "the file holds {} values; this scene's cache has {}",
            values.len(),
            cache.values_len()
        );
        transfer::write_buffer(&self.device, &self.scene.cache.values, values).context("upload the radiance cache")?;
        self.cache_solved = true;
        self.kept = Some(Some((frame.indirect, frame.background, stats)));
        Ok(())
    }

    /// Senses the radiance cache's bounces for `frame`'s global illumination, leaving the cache for the
    /// sensor maps that follow ([`Renderer::render`] does this itself; [`Renderer::sense_at`] then sees it).
    /// An error if the renderer was built without a cache.
    pub fn solve_cache(&mut self, frame: &FrameParams, progress: &dyn Progress) -> Result<Option<GiStats>> {
        self.cache_solved = false;
        let Some(bounces) = frame.indirect.bounces() else { return Ok(None) };
        let background = self.background(frame);
        let (cache, later) = self.cache.as_mut().context(
            "this renderer was built without a radiance cache (RendererBuilder::radiance_cache): it renders the \
             paper's ε only",
        )?;
        // Only the entries light reaches are sensed: the walk starts at the emitters' entries, and where
        // rays that leave the scene carry light, at the entries that see out.
        let distant_lights = self.host.mesh.local_triangles().len() < self.host.mesh.triangles.len();
        let sky = !background.is_black() || distant_lights;
        let (bias, near) = self.estimate.offsets;
        let seeds = crate::gi::reach::seeds(cache, &self.host.mesh, &self.bvh, sky, bias);
        let runners = Runners { first: &mut self.runner, later };
        let budget = self.config.cache.map_or(crate::gi::transport::DEFAULT_BUDGET, |c| c.transport_budget);
        let light = (bounces, background, budget);
        // Where the light hints have points on the lights, an uneven piece's direct light is measured by
        // shadow rays from the points spread over it rather than by sensors there.
        let (lights, bvh) = (&self.scene.lights, &self.bvh);
        let bits = hints::group_bits(lights);
        let bits = &bits;
        let shadow = ShadowPoints::with_count(lights, SHADOW_POINTS);
        let shadow = &shadow;
        let direct = |points: &[LightPoint], p: Vec3, n: Vec3| -> Vec3 {
            let (facing, seen) = hints::masks(bvh, points, (p, n), bias, near);
            let e = lights.unoccluded(p + n * bias, n);
            let share = |(group, &g): (usize, &u64)| match ((facing & g).count_ones(), (seen & g).count_ones()) {
                (0, _) => 1.0,
                (f, s) if s == f => 1.0,
                (_, 0) => shadow.share_if_seen(bvh, (p, n), (bias, near), group).unwrap_or(0.0),
                _ => shadow.share(bvh, (p, n), (bias, near), group).unwrap_or(0.0),
            };
            bits.iter().enumerate().zip(e).map(|(g, e)| e * share(g)).sum::<Vec3>() / std::f32::consts::PI
        };
        let points = self.light_points.as_deref().filter(|_| self.estimate.direct_by_rays);
        let rays = points.map(|points| move |p: Vec3, n: Vec3| direct(points, p, n));
        let rays = rays.as_ref().map(|f| f as DirectByRays<'_>);
        // Where a piece's light varies over it, its mean (`gi::piece_mean`), seen as the sensor maps see it.
        let sky = self.host.sky.as_ref();
        let background = move |d: Vec3| match (background, sky) {
            (Background::Constant(c), _) => c,
            (Background::SkyMap, Some(sky)) => sky.radiance(d),
            (Background::SkyMap, None) => Vec3::ZERO,
        };
        let around = Surroundings {
            bvh,
            triangles: &self.host.mesh.triangles,
            local: self.host.mesh.local_triangles().len(),
            offsets: (bias, near),
            background: &background,
        };
        let light_rays = (rays, Some(&around));
        let stats = solve(&self.device, runners, (cache, &self.scene.cache, seeds), light, light_rays, progress)?;
        self.cache_solved = true;
        Ok(Some(stats))
    }
}
