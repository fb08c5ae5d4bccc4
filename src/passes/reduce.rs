//! Reduction pass (docs/DESIGN.md §3 step 4): each sensor's layers → R at the sensor's pixel of the radiance
//! map and in the batch's results: `(1/π) Σ Ck·w` over its main layers (the paper's estimator), plus, with
//! the exact estimator, each light group's exact irradiance times its visibility read from the sensor's zoom
//! pair. Shader: `glsl/reduce.comp` (one workgroup per sensor, tree reduction in shared memory). One
//! descriptor set per batch in flight, each bound to that batch's maps, pixels, sensors and results.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use super::sensor_maps::{MapLayout, StrategyDesc};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::ReducePush;
use crate::sensors::layout::SensorLayout;
use crate::sensors::weights;
use crate::shaders;
use crate::vk::{Buffer, ComputeKernel, Device, Encoder, Image, transfer};

pub struct ReducePass {
    kernel: ComputeKernel,
    /// f32 weight per texel of one sensor's main layers ([layer][row][col]).
    weights: Buffer,
    /// Per texel of the main layers: its direction in the sensor frame and its solid angle (`vec4`), where
    /// it sees the sky map.
    directions: Buffer,
    /// The scene's sky map: its table entry and texels.
    sky: (Arc<Buffer>, Arc<Buffer>),
    /// The scene's light groups (their ranges of emitter chunks), and how many chunks it has.
    groups: Arc<Buffer>,
    chunks: u32,
    /// The maps' `Ke` scale (`sensor_maps::emission_scale`), multiplied back on emitter texels.
    emission_scale: f32,
    rd: u32,
    layout: SensorLayout,
}

/// What one batch's reduction reads and writes.
pub struct ReduceBindings<'a> {
    /// The batch's sensor maps.
    pub maps: &'a Image,
    /// Radiance-map pixel of each sensor of the batch (u32).
    pub pixels: &'a Buffer,
    /// R and visibilities of each sensor of the batch (`GpuSensorResult`), for the host.
    pub results: &'a Buffer,
    /// Each sensor's frame (`GpuSensor`) and its zoom views (`GpuZoom`, `[sensor][group]`).
    pub sensors: &'a Buffer,
    pub zooms: &'a Buffer,
    /// The emitter pass's irradiance (`vec4` per sensor and chunk).
    pub irradiance: &'a Buffer,
    /// The radiance map of the current render, and its indirect part (the main layers' share).
    pub radiance: &'a Buffer,
    pub indirect: &'a Buffer,
}

impl ReducePass {
    /// For sensors described by `desc` in `scene`, with one descriptor set for each of `slots` batches in
    /// flight.
    pub fn new(device: &Arc<Device>, scene: &GpuScene, desc: &StrategyDesc, slots: u32) -> Result<Self> {
        let (layout, rd) = (desc.layout, desc.rd);
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let mut bindings = vec![(0, vk::DescriptorType::STORAGE_IMAGE)];
        bindings.extend((1..=12).map(|b| (b, storage)));
        let kernel =
            ComputeKernel::new(device, shaders::REDUCE_COMP, &bindings, size_of::<ReducePush>() as u32, slots)?;
        let w: Vec<f32> = weights::sensor_weights(layout.kind, rd).into_iter().map(|w| w as f32).collect();
        let weights = transfer::upload(device, "texel weights", &w, vk::BufferUsageFlags::STORAGE_BUFFER)?;
        let d = weights::texel_directions(layout.kind, rd);
        let directions = transfer::upload(device, "texel directions", &d, vk::BufferUsageFlags::STORAGE_BUFFER)?;
        let emission_scale = super::sensor_maps::emission_scale(scene, desc.fronts);
        Ok(Self {
            kernel,
            weights,
            directions,
            sky: (scene.sky.clone(), scene.sky_texels.clone()),
            groups: scene.groups.clone(),
            chunks: scene.chunk_count,
            emission_scale,
            rd,
            layout,
        })
    }

    /// Binds slot `slot`'s resources (call while that slot's work is not in flight).
    pub fn bind(&self, device: &Device, slot: usize, b: &ReduceBindings<'_>) {
        self.kernel
            .writer(slot)
            .storage_image(0, b.maps.view)
            .storage_buffer(1, &self.weights)
            .storage_buffer(2, b.pixels)
            .storage_buffer(3, b.radiance)
            .storage_buffer(4, b.results)
            .storage_buffer(5, b.sensors)
            .storage_buffer(6, b.zooms)
            .storage_buffer(7, b.irradiance)
            .storage_buffer(8, &self.groups)
            .storage_buffer(9, b.indirect)
            .storage_buffer(10, &self.directions)
            .storage_buffer(11, &self.sky.0)
            .storage_buffer(12, &self.sky.1)
            .apply(device);
    }

    /// Records the reduction of the first `count` sensors of slot `slot`'s batch, whose maps lie as `layout`;
    /// `entries`: their main layers hold the radiance cache's entries (`CacheRead::Entries`), no light.
    pub fn record(&self, enc: &Encoder<'_>, slot: usize, (layout, entries): (MapLayout, bool), count: u32) {
        let atlas_columns = match layout {
            MapLayout::Layers => 0,
            MapLayout::Atlas { columns } => columns,
        };
        let push = ReducePush {
            rd: self.rd,
            layers: self.layout.layers(),
            main_layers: self.layout.main_layers(),
            atlas_columns,
            groups: self.layout.groups,
            chunks: self.chunks,
            emission_scale: self.emission_scale,
            main_entries: entries as u32,
        };
        self.kernel.dispatch(enc, slot, &push, [count, 1, 1]);
    }
}
