//! The batch runner: senses lists of pixels in batches, several in flight. Each of its slots owns one
//! batch's resources — sensor maps, views, pixel list, results, reduction descriptor set, command buffer,
//! fence and timestamps — so that while the device renders one batch the host builds and records the next.
//!
//! ```text
//!   host:    [views+record b0][views+record b1] wait b0 → R(b0) [views+record b2] wait b1 → R(b1) …
//!   device:                  [maps b0 | reduce b0][maps b1 | reduce b1][maps b2 | reduce b2] …
//! ```
//!
//! A batch is recorded as [culling →] [emitters →] sensor maps (the strategy) → barrier → reduction, which
//! writes each sensor's R into the radiance map and into the slot's results, which the host reads when the
//! slot is next waited on: a round of refinement reads back exactly the values it sensed, nothing more.
//! When the scene is drawn from its clusters, the culling pass first writes each view's draw list into the
//! slot (compute write → indirect read), and the runner reads back each view's count with the results.

use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context as _, Result, ensure};
use ash::vk;
use gpu_allocator::MemoryLocation;
use serde::Serialize;

use crate::cancel::{Cancelled, Reason};
use crate::gbuffer::GBufferData;
use crate::gpu_scene::GpuScene;
use crate::gpu_types::{CullPush, GpuSensor, GpuSensorResult, GpuZoom};
use crate::passes::cull::{COUNT_BLOCKS, CullBindings, CullPass};
use crate::passes::emitters::{EmitterBindings, EmitterPass};
use crate::passes::reduce::{ReduceBindings, ReducePass};
use crate::passes::sensor_maps::{self, CacheRead, CkParams, SlotMaps, Strategy, StrategyDesc};
use crate::passes::transport::TransportPass;
use crate::scene::Aabb;
use crate::sensors::SensorKind;
use crate::sensors::frame::{self, SensorFrame};
use crate::sensors::views::BatchViews;
use crate::strategy::StrategyKind;
use crate::vk::{Access, Buffer, CommandSlot, Device, TimestampQueries, barrier};

/// Timestamps per batch: start, culling done (at once where nothing is culled), sensor maps done, reduction
/// done.
const TIMESTAMPS: u32 = 4;

/// What the batches of a render cost, split between host and device.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BatchTimes {
    pub batches: u64,
    /// Host: building views, recording and submitting.
    pub host_record: Duration,
    /// Host: waiting for batches to complete.
    pub host_wait: Duration,
    /// Device, by timestamp queries: the culling pass (`None` also where nothing is culled), the sensor maps
    /// (the emitter pass included) and the reduction. `None` where the device cannot write timestamps.
    pub gpu_cull: Option<Duration>,
    pub gpu_maps: Option<Duration>,
    pub gpu_reduction: Option<Duration>,
    /// Bytes read back to the host (each batch's results).
    pub readback_bytes: u64,
    /// Culled: the triangles the sensor maps drew, all views of all batches (`None` at full detail), and
    /// those of the clusters the culling pass selected (as many without the triangle pass).
    pub drawn_triangles: Option<u64>,
    pub selected_triangles: Option<u64>,
    /// Clusters the triangle pass left whole, their view's region of its pool being full (drawn, slower).
    pub whole_clusters: u64,
}

/// What a render's reductions write, a `vec4` per pixel each (w: `gpu_types::radiance_state`): R, and its
/// indirect part, the main layers' share (all but the exact estimator's emitter term).
#[derive(Clone)]
pub struct SensedMaps {
    pub radiance: Arc<Buffer>,
    pub indirect: Arc<Buffer>,
}

/// A completed batch, as the host reads it back.
pub(crate) struct Sensed<'a> {
    /// Its sensors' pixels, and what the reduction found there.
    pub pixels: &'a [u32],
    pub results: &'a [GpuSensorResult],
    /// Drawn with [`CacheRead::Entries`]: the cache value each texel of each sensor's main layers sees
    /// (`passes::transport`, [`BatchRunner::texels_per_sensor`] a sensor); else empty.
    pub texels: &'a [u32],
}

/// Receives each completed batch.
pub(crate) type Deliver<'a> = &'a mut dyn FnMut(&Sensed<'_>);

struct Slot {
    commands: CommandSlot,
    maps: SlotMaps,
    /// Radiance-map pixel of each sensor of the batch, host-written.
    pixels: Buffer,
    /// Each sensor's frame and its zoom views, host-written, for the emitter pass and the reduction.
    sensors: Buffer,
    zooms: Buffer,
    /// The emitter pass's irradiance, per sensor and emitter chunk.
    irradiance: Buffer,
    /// R and visibilities of each sensor of the batch (`GpuSensorResult`), device-written, host-read.
    results: Buffer,
    /// With [`BatchRunner::with_rows`]: the cache value each main-layer texel sees, device-written,
    /// host-read, for batches drawn with [`CacheRead::Entries`].
    texels: Option<Buffer>,
    timestamps: Option<TimestampQueries>,
    /// Pixels of the batch in flight; empty when the slot is idle.
    in_flight: Vec<u32>,
    /// Whether the batch in flight was drawn with [`CacheRead::Entries`].
    entries: bool,
}

/// The culling pass and the clusters and tree it reads, when the maps are drawn from them.
struct Culling {
    pass: CullPass,
    reads: [Arc<Buffer>; 3],
}

pub(crate) struct BatchRunner {
    // Field order is drop order: the slots wait for their work before anything they use goes.
    slots: Vec<Slot>,
    next: usize,
    strategy: Box<dyn Strategy>,
    /// The exact estimator's closed-form emitter term (`None` with the paper's).
    emitters: Option<EmitterPass>,
    culling: Option<Culling>,
    reduce: ReducePass,
    /// Copies the texels' cache entries, where the runner reads the transport's rows
    /// ([`BatchRunner::with_rows`]).
    transport: Option<TransportPass>,
    /// How far a sensor sits above its surface, and its views' near plane (world units).
    bias: f32,
    near: f32,
    desc: StrategyDesc,
    /// Turn each sensor about its normal by its pixel's turn (`frame::pixel_turn`): hemicubes of the exact
    /// estimator, whose domain a turn leaves as it is.
    turn: bool,
    /// Bounding box of each light group measured.
    groups: Vec<Aabb>,
    /// The maps the reductions write: every batch submitted keeps them alive until its fence signals, so a
    /// render that fails with batches in flight cannot free them under the device.
    radiance: Option<SensedMaps>,
    device: Arc<Device>,
    pub times: BatchTimes,
}

impl BatchRunner {
    /// A runner for `kind` with `in_flight` slots, each holding one batch as `desc` sizes it; sensors sit
    /// `bias` above their surfaces and see from `near` on.
    pub fn new(
        device: &Arc<Device>,
        scene: &GpuScene,
        kind: StrategyKind,
        desc: StrategyDesc,
        in_flight: u32,
        (bias, near): (f32, f32),
    ) -> Result<Self> {
        ensure!(in_flight >= 1, "at least one batch must be in flight");
        let strategy = sensor_maps::create(kind, device, scene, desc)?;
        let capacity = strategy.capacity() as u64;
        let reduce = ReducePass::new(device, scene, &desc, in_flight)?;
        let measures = desc.exact() && desc.layout.groups > 0;
        let emitters = measures.then(|| EmitterPass::new(device, scene, in_flight)).transpose()?;
        let irradiance_bytes = emitters.as_ref().map_or(0, |e| e.bytes_per_sensor()) * capacity;
        let groups: Vec<Aabb> =
            scene.lights.groups.iter().take(desc.layout.groups as usize).map(|g| g.bounds).collect();
        let host = |name, bytes: u64, location| {
            Buffer::new(device, name, bytes, vk::BufferUsageFlags::STORAGE_BUFFER, location)
        };
        let slots = (0..in_flight)
            .map(|_| -> Result<Slot> {
                Ok(Slot {
                    commands: CommandSlot::new(device)?,
                    maps: strategy.new_slot()?,
                    pixels: host("sensor pixels", 4 * capacity, MemoryLocation::CpuToGpu)?,
                    sensors: host("sensor frames", size_of::<GpuSensor>() as u64 * capacity, MemoryLocation::CpuToGpu)?,
                    zooms: host(
                        "sensor zoom views",
                        size_of::<GpuZoom>() as u64 * capacity * groups.len() as u64,
                        MemoryLocation::CpuToGpu,
                    )?,
                    irradiance: Buffer::new(
                        device,
                        "emitter irradiance",
                        irradiance_bytes,
                        vk::BufferUsageFlags::STORAGE_BUFFER,
                        MemoryLocation::GpuOnly,
                    )?,
                    results: host(
                        "sensor results",
                        size_of::<GpuSensorResult>() as u64 * capacity,
                        MemoryLocation::GpuToCpu,
                    )?,
                    texels: None,
                    timestamps: TimestampQueries::new(device, TIMESTAMPS)?,
                    in_flight: Vec::new(),
                    entries: false,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        // The strategy draws from the clusters (its slots have draw lists) only if the scene has them.
        let culling = match (&scene.clusters, slots[0].maps.draws()) {
            (Some(c), Some(_)) => {
                let pass = CullPass::new(device, in_flight, c.tree.clone())?;
                for (i, slot) in slots.iter().enumerate() {
                    let draws = slot.maps.draws().context("every slot of a culled strategy has draw lists")?;
                    let bindings = CullBindings {
                        clusters: &c.clusters,
                        nodes: &c.nodes,
                        items: &c.items,
                        views: slot.maps.views(),
                        sensors: &slot.sensors,
                        commands: &draws.commands,
                        counts: &draws.counts,
                        queue: &draws.queue,
                        walk: &draws.walk,
                        kept: &draws.kept,
                        vertices: &c.vertices,
                        indices: &c.indices,
                        pool: &draws.pool,
                        regions: &draws.regions,
                        region_draws: &draws.region_draws,
                    };
                    pass.bind(device, i, &bindings);
                }
                Some(Culling { pass, reads: [c.clusters.clone(), c.nodes.clone(), c.items.clone()] })
            }
            _ => None,
        };
        Ok(Self {
            slots,
            next: 0,
            strategy,
            emitters,
            culling,
            reduce,
            transport: None,
            bias,
            near,
            desc,
            turn: desc.exact() && desc.layout.kind == SensorKind::Hemicube,
            groups,
            radiance: None,
            device: device.clone(),
            times: BatchTimes::default(),
        })
    }

    /// The runner, able to sense with [`CacheRead::Entries`] too: each slot gets a texel list, a `u32` per
    /// texel of its sensors' main layers (half its maps' colour bytes at most).
    pub fn with_rows(mut self) -> Result<Self> {
        let pass = TransportPass::new(&self.device, &self.desc, self.slots.len() as u32)?;
        let bytes = 4 * (pass.texels_per_sensor() * self.capacity() as usize) as u64;
        for (i, slot) in self.slots.iter_mut().enumerate() {
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let texels = Buffer::new(&self.device, "texel entries", bytes, usage, MemoryLocation::GpuToCpu)?;
            pass.bind(&self.device, i, &slot.maps.maps, &texels);
            slot.texels = Some(texels);
        }
        self.transport = Some(pass);
        Ok(self)
    }

    /// Texels of one sensor in [`Sensed::texels`]: its main layers', each `rd × rd`, row by row.
    pub fn texels_per_sensor(&self) -> usize {
        (self.desc.layout.main_layers() * self.desc.rd * self.desc.rd) as usize
    }

    /// The layout of its sensors (kind and light groups).
    pub fn layout(&self) -> crate::sensors::layout::SensorLayout {
        self.desc.layout
    }

    pub fn kind(&self) -> StrategyKind {
        self.strategy.kind()
    }

    /// rd of its sensor maps.
    pub fn sensor_size(&self) -> u32 {
        self.desc.rd
    }

    /// Sensors per batch.
    pub fn capacity(&self) -> u32 {
        self.strategy.capacity()
    }

    /// Whether the sensor maps are drawn from the scene's clusters, culled per view.
    pub fn culled(&self) -> bool {
        self.culling.is_some()
    }

    pub fn in_flight(&self) -> u32 {
        self.slots.len() as u32
    }

    /// Makes the reductions write into `maps` (a render's radiance map and its indirect part) and resets the
    /// times. No batch may be in flight: [`BatchRunner::drain`] first.
    pub fn bind(&mut self, maps: &SensedMaps) -> Result<()> {
        let (radiance, indirect) = (&maps.radiance, &maps.indirect);
        ensure!(self.slots.iter().all(|s| s.in_flight.is_empty()), "bind with batches in flight");
        for (i, slot) in self.slots.iter().enumerate() {
            let bindings = ReduceBindings {
                maps: &slot.maps.maps,
                pixels: &slot.pixels,
                results: &slot.results,
                sensors: &slot.sensors,
                zooms: &slot.zooms,
                irradiance: &slot.irradiance,
                radiance,
                indirect,
            };
            self.reduce.bind(&self.device, i, &bindings);
            if let Some(emitters) = &self.emitters {
                let bindings =
                    EmitterBindings { sensors: &slot.sensors, zooms: &slot.zooms, irradiance: &slot.irradiance };
                emitters.bind(&self.device, i, &bindings);
            }
        }
        self.radiance = Some(maps.clone());
        self.times = BatchTimes { drawn_triangles: self.culling.as_ref().map(|_| 0), ..BatchTimes::default() };
        Ok(())
    }

    /// Senses a sensor at each of `pixels` (indices into `g`) in batches, handing each completed batch's
    /// pixels and results to `deliver`. Returns with up to all slots' batches still in flight.
    pub fn sense(&mut self, g: &GBufferData, pixels: &[u32], ck: CkParams, deliver: Deliver<'_>) -> Result<()> {
        let radiance = self.radiance.clone().context("sense before bind: no radiance map to write")?;
        let entries = ck.cache == CacheRead::Entries;
        ensure!(!entries || self.transport.is_some(), "sensing the cache's entries needs a runner with_rows");
        for chunk in pixels.chunks(self.capacity() as usize) {
            let index = self.next;
            self.next = (self.next + 1) % self.slots.len();
            self.retire(index, deliver)?;

            let start = Instant::now();
            let width = g.size.width;
            let frames: Vec<SensorFrame> = chunk
                .iter()
                .map(|&i| {
                    let p = (g.position[i as usize].truncate(), g.normal[i as usize].truncate());
                    let frame = SensorFrame::new(p.0, p.1, self.bias);
                    if self.turn { frame.turned(frame::pixel_turn(i % width, i / width)) } else { frame }
                })
                .collect();
            let views = BatchViews::new(&frames, &self.desc.layout, self.near, &self.groups, self.desc.rd);
            let (strategy, emitters, reduce, culling) = (&self.strategy, &self.emitters, &self.reduce, &self.culling);
            let transport = self.transport.as_ref().filter(|_| entries);
            let (rd, near) = (self.desc.rd, self.near);
            let slot = &mut self.slots[index];
            slot.pixels.write(0, chunk)?;
            slot.sensors.write(0, &views.sensors)?;
            slot.zooms.write(0, &views.zooms)?;
            let (maps, timestamps) = (&mut slot.maps, &slot.timestamps);
            slot.commands.record(|enc| {
                let stamp = |query, stage| timestamps.iter().for_each(|t| enc.timestamp(t, query, stage));
                timestamps.iter().for_each(|t| enc.reset_queries(t));
                stamp(0, vk::PipelineStageFlags::TOP_OF_PIPE);
                // Each view's draw list, before the maps that draw it (the pass ends on compute write →
                // indirect read).
                if let (Some(c), Some(draws)) = (culling, maps.draws()) {
                    let push = CullPush {
                        views: views.views.len() as u32,
                        per_sensor: views.per_sensor as u32,
                        max_per_view: draws.max_per_view,
                        rd,
                        near,
                        region: draws.region,
                        ..Default::default()
                    };
                    let zero = (!draws.count_buffer).then_some(&draws.commands);
                    c.pass.record(enc, index, (&draws.counts, &draws.walk, &draws.kept), zero, &push);
                }
                stamp(1, vk::PipelineStageFlags::BOTTOM_OF_PIPE);
                // The emitters' closed form needs no map: it runs before the maps.
                if let Some(emitters) = emitters {
                    emitters.record(enc, index, chunk.len() as u32);
                }
                strategy.record(enc, maps, &views, ck)?;
                stamp(2, vk::PipelineStageFlags::BOTTOM_OF_PIPE);
                barrier::global(enc, &[Access::ColorAttachmentWrite, Access::ComputeWrite], &[Access::ComputeRead]);
                reduce.record(enc, index, (strategy.map_layout(), entries), chunk.len() as u32);
                if let Some(t) = transport {
                    t.record(enc, index, strategy.map_layout(), chunk.len() as u32);
                }
                stamp(3, vk::PipelineStageFlags::BOTTOM_OF_PIPE);
                // The results (and the radiance map) are read by the host, or copied, once the fence signals.
                barrier::global(enc, &[Access::ComputeWrite], &[Access::HostRead, Access::TransferRead]);
                Ok(())
            })?;
            slot.commands.submit()?;
            slot.commands.retire(radiance.radiance.clone());
            slot.commands.retire(radiance.indirect.clone());
            for read in self.culling.iter().flat_map(|c| &c.reads) {
                slot.commands.retire(read.clone());
            }
            slot.in_flight = chunk.to_vec();
            slot.entries = entries;
            self.times.batches += 1;
            self.times.host_record += start.elapsed();
        }
        Ok(())
    }

    /// [`BatchRunner::sense`], asking `stop` before each batch. When it gives a reason, waits for the batches
    /// in flight (their results dropped: the work is abandoned) and returns [`Cancelled`]: the device is idle
    /// and every object is left to its owner.
    pub fn sense_or_stop(
        &mut self,
        g: &GBufferData,
        pixels: &[u32],
        ck: CkParams,
        deliver: Deliver<'_>,
        stop: &dyn Fn() -> Option<Reason>,
    ) -> Result<()> {
        for chunk in pixels.chunks(self.capacity().max(1) as usize) {
            if let Some(reason) = stop() {
                self.drain(&mut |_| ())?;
                return Err(Cancelled(reason).into());
            }
            self.sense(g, chunk, ck, deliver)?;
        }
        Ok(())
    }

    /// Waits for every batch in flight, handing its results to `deliver`.
    pub fn drain(&mut self, deliver: Deliver<'_>) -> Result<()> {
        // Oldest first: the slot after the last one used.
        for k in 0..self.slots.len() {
            self.retire((self.next + k) % self.slots.len(), deliver)?;
        }
        Ok(())
    }

    /// Waits for slot `index`'s batch, if any, and delivers its results and times.
    fn retire(&mut self, index: usize, deliver: Deliver<'_>) -> Result<()> {
        let per_sensor = self.texels_per_sensor();
        let slot = &mut self.slots[index];
        self.times.host_wait += slot.commands.wait()?;
        if slot.in_flight.is_empty() {
            return Ok(());
        }
        let pixels = std::mem::take(&mut slot.in_flight);
        let r: Vec<GpuSensorResult> = slot.results.read(pixels.len())?;
        self.times.readback_bytes += size_of_val(r.as_slice()) as u64;
        let texels: Vec<u32> = match (&slot.texels, slot.entries) {
            (Some(t), true) => t.read(pixels.len() * per_sensor)?,
            _ => Vec::new(),
        };
        self.times.readback_bytes += size_of_val(texels.as_slice()) as u64;
        if let Some(t) = slot.timestamps.as_ref().map(TimestampQueries::read_seconds).transpose()?.flatten() {
            let add = |total: &mut Option<Duration>, seconds: f64| {
                *total = Some(total.unwrap_or_default() + Duration::from_secs_f64(seconds.max(0.0)));
            };
            if self.culling.is_some() {
                add(&mut self.times.gpu_cull, t[1] - t[0]);
                add(&mut self.times.gpu_maps, t[2] - t[1]);
            } else {
                add(&mut self.times.gpu_maps, t[2] - t[0]);
            }
            add(&mut self.times.gpu_reduction, t[3] - t[2]);
        }
        if let (Some(total), Some(draws)) = (&mut self.times.drawn_triangles, slot.maps.draws()) {
            let views = pixels.len() * self.desc.layout.views() as usize;
            let counts: Vec<u32> = draws.counts.read(COUNT_BLOCKS as usize * views)?;
            let block = |b: usize| &counts[b * views..(b + 1) * views];
            let triangle_pass = draws.region > 0;
            // The slots are sized by a bound no selection exceeds; a view beyond it would have lost geometry.
            let walked = block(if triangle_pass { 5 } else { 0 });
            if let Some(v) = walked.iter().position(|&n| n > draws.max_per_view) {
                anyhow::bail!(
                    "sensor view {v} selected {} clusters, more than the {} its draw list holds: a bug in the cluster \
                     bound or the culling pass; nothing was written",
                    walked[v],
                    draws.max_per_view
                );
            }
            let sum = |b: usize| block(b).iter().map(|&n| n as u64).sum::<u64>();
            let selected = sum(1);
            // Without the triangle pass the maps draw what the walk selected.
            let drawn = if triangle_pass { sum(2) } else { selected };
            *total += drawn;
            *self.times.selected_triangles.get_or_insert(0) += selected;
            if triangle_pass {
                self.times.whole_clusters += sum(4);
            }
        }
        deliver(&Sensed { pixels: &pixels, results: &r, texels: &texels });
        Ok(())
    }

    /// Runs the reduction alone over slot 0's first `count` sensors again (their maps are still in place
    /// after a sense), into a scratch radiance map; returns the time from submission to completion.
    pub fn time_reduction(&mut self, count: u32) -> Result<Duration> {
        self.drain(&mut |_| ())?;
        let count = count.min(self.capacity());
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let scratch = Buffer::new(&self.device, "scratch radiance", 16 * count as u64, usage, MemoryLocation::GpuOnly)?;
        let scratch_indirect =
            Buffer::new(&self.device, "scratch indirect", 16 * count as u64, usage, MemoryLocation::GpuOnly)?;
        let slot = &self.slots[0];
        // The pixel list still names the last batch's pixels: point them into the scratch map instead.
        let pixels: Vec<u32> = (0..count).collect();
        let mut list = Buffer::new(&self.device, "scratch pixels", 4 * count as u64, usage, MemoryLocation::CpuToGpu)?;
        list.write(0, &pixels)?;
        let bindings = ReduceBindings {
            maps: &slot.maps.maps,
            pixels: &list,
            results: &slot.results,
            sensors: &slot.sensors,
            zooms: &slot.zooms,
            irradiance: &slot.irradiance,
            radiance: &scratch,
            indirect: &scratch_indirect,
        };
        self.reduce.bind(&self.device, 0, &bindings);
        self.radiance = None; // slot 0 no longer writes the bound map: bind again before sensing
        let layout = self.strategy.map_layout();
        let time = self.device.submit_and_wait(|enc| {
            self.reduce.record(enc, 0, (layout, false), count);
            Ok(())
        })?;
        Ok(time)
    }
}
