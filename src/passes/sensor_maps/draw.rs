//! What the strategies draw the sensor maps from: the scene's vertices or its clusters (their draw lists,
//! filled by the culling pass), materials, radiance cache and textures, and the pipeline that draws them.

#[allow(clippy::wildcard_imports)]
use super::*;
use crate::passes::cull::COUNT_BLOCKS;
use crate::passes::cull_triangles::KEPT_HEADER_BYTES;

/// Triangles a view's region of the triangle pass's pool holds per texel of the view, within
/// [`REGION_MIN`]..=[`REGION_MAX`]: a triangle drawn covers a texel centre, several a texel where they lie behind one
/// another, as the far side of any closed mesh does (back faces are drawn). At rd 32 a sensor drew 0.25 a
/// texel in the 0.55M hall and 2 in Crytek Sponza, whose views left 285 clusters a sensor whole at 2 a
/// texel (docs/BENCHMARKS.md). Beyond it, clusters are drawn whole: slower, never wrong.
pub const REGION_PER_TEXEL: u32 = 8;
/// The fewest triangles a view's region holds: at rd 16 Sponza's views left 72 clusters a sensor whole at
/// 8 a texel.
pub const REGION_MIN: u32 = 4_096;
/// The most triangles a view's region holds: at large rd the triangles a view draws are far fewer than its
/// texels (0.07 a texel in the hall at rd 64), and the pool would bound the batch (one storage buffer).
pub const REGION_MAX: u32 = 16_384;

/// Indices in a view's region of the triangle pass's pool (0: no triangle pass), before one storage
/// buffer's range caps it.
fn region(culled: &Culled) -> u32 {
    let triangles = (REGION_PER_TEXEL * culled.rd * culled.rd).clamp(REGION_MIN, REGION_MAX);
    if culled.cull_triangles { 3 * triangles } else { 0 }
}

/// Bytes per sensor of what draws the maps from clusters.
#[derive(Clone, Copy, Debug, Default)]
pub struct DrawBytes {
    /// Its draw lists and the culling walk's queue, and the triangle pass's pool: storage buffers, whose
    /// range bounds a batch.
    pub lists: u64,
    pub pool: u64,
    /// All of it: the lists, the triangle pass's list, pool and regions.
    pub memory: u64,
}

/// One batch's indexed indirect draws: `max_per_view` command slots per view, and per view its number of
/// draws and (after them, for statistics) of triangles, written by the culling and triangle passes.
pub struct DrawLists {
    /// `GpuDrawCommand`s, view-major (device-local).
    pub commands: Buffer,
    /// `passes::cull::COUNT_BLOCKS` `u32` per view of the largest batch (host-readable: the runner checks
    /// the walk's draws for overflow and sums the triangles).
    pub counts: Buffer,
    pub max_per_view: u32,
    /// The device reads each view's count (`drawIndirectCount`); else every slot is drawn, the unused
    /// ones zeroed by the culling pass.
    pub count_buffer: bool,
    /// The culling pass's walk: its queue of (node, view) pairs and its per-depth counts (device-local).
    pub queue: Buffer,
    pub walk: Buffer,
    /// The commands the walk wrote, for the triangle pass (`passes::cull_triangles`; device-local).
    pub kept: Buffer,
    /// The triangle pass's index pool, `region` indices per view (0: no triangle pass), each view's
    /// command over its region, and how many of it to draw (1, or 0 where empty).
    pub pool: Buffer,
    pub region: u32,
    pub regions: Buffer,
    pub region_draws: Buffer,
}

impl DrawLists {
    /// Lists for `views` views: each view's region of the triangle pass's pool has room for
    /// [`REGION_PER_TEXEL`] triangles per texel, within one storage buffer's range; a cluster beyond its
    /// view's region is drawn whole.
    pub(super) fn new(device: &Arc<Device>, views: u32, culled: &Culled) -> Result<Self> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::INDIRECT_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST;
        let slots = views as u64 * culled.max_per_view as u64;
        let bytes = slots * size_of::<GpuDrawCommand>() as u64;
        let (storage, local) = (vk::BufferUsageFlags::STORAGE_BUFFER, MemoryLocation::GpuOnly);
        let queue = culled.tree.queue_bytes(views as u64);
        let range = device.adapter.limits.max_storage_buffer_range as u64;
        let region = (region(culled) as u64).min(range / 4 / views.max(1) as u64) as u32;
        let region = if region >= 3 { region } else { 0 };
        let pool_bytes = (4 * region as u64 * views as u64).max(4);
        let pool_usage = vk::BufferUsageFlags::INDEX_BUFFER | storage;
        Ok(Self {
            commands: Buffer::new(device, "sensor draw lists", bytes, usage, local)?,
            counts: Buffer::new(
                device,
                "sensor draw counts",
                4 * COUNT_BLOCKS * views as u64,
                usage,
                MemoryLocation::GpuToCpu,
            )?,
            max_per_view: culled.max_per_view,
            count_buffer: culled.count_buffer,
            queue: Buffer::new(device, "culling queue", queue, storage, local)?,
            walk: Buffer::new(device, "culling walk", culled.tree.walk_bytes(), usage, local)?,
            kept: Buffer::new(device, "culling kept", KEPT_HEADER_BYTES + 4 * slots, usage, local)?,
            pool: Buffer::new(device, "sensor triangle pool", pool_bytes, pool_usage, local)?,
            region,
            regions: Buffer::new(device, "sensor draw regions", views as u64 * 20, usage, local)?,
            region_draws: Buffer::new(device, "sensor region draws", views as u64 * 4, usage, local)?,
        })
    }
}

/// The cluster hierarchy a culled pipeline draws from.
pub(super) struct Culled {
    pub(super) vertices: Arc<Buffer>,
    /// Their texture coordinates, for textures and cut-outs.
    pub(super) uvs: Arc<Buffer>,
    pub(super) indices: Arc<Buffer>,
    pub(super) max_per_view: u32,
    pub(super) count_buffer: bool,
    pub(super) tree: TreeShape,
    /// Run the triangle pass (`StrategyDesc::cull_triangles`) for views of `rd × rd` texels.
    pub(super) cull_triangles: bool,
    pub(super) rd: u32,
}

/// What every strategy draws the maps from: the scene's vertices (or clusters), materials, radiance cache
/// and textures, and how emitters are written.
pub(super) struct SensorInputs {
    /// The scene's vertices, materials and radiance cache (the slots' descriptor sets name all but the
    /// first).
    pub(super) vertices: Arc<Buffer>,
    pub(super) vertex_count: u32,
    /// The soup's texture coordinates, for textures and cut-outs.
    pub(super) uvs: Arc<Buffer>,
    pub(super) surfaces: Arc<Buffer>,
    pub(super) cache: [Arc<Buffer>; 3],
    /// The texture table and texels, for textures and cut-outs.
    pub(super) textures: [Arc<Buffer>; 2],
    /// The exact estimator: emitter fronts leave 0 and their group.
    pub(super) exact: bool,
    /// The paper's estimator: maps hold `Ke` divided by this ([`emission_scale`]).
    pub(super) emission_scale: f32,
    /// Drawn from the scene's clusters, view by view; `None`: the whole soup.
    pub(super) culled: Option<Culled>,
    pub(super) device: Arc<Device>,
}

impl SensorInputs {
    /// `cull`: draw from the scene's clusters where it has them.
    pub(super) fn new(device: &Arc<Device>, scene: &GpuScene, desc: &StrategyDesc, cull: bool) -> Self {
        Self {
            vertices: scene.vertices.clone(),
            vertex_count: scene.vertex_count,
            surfaces: scene.surfaces.clone(),
            cache: [scene.cache.table.clone(), scene.cache.values.clone(), scene.cache.splits.clone()],
            textures: [scene.textures.clone(), scene.texels.clone()],
            exact: desc.exact(),
            emission_scale: emission_scale(scene, desc.fronts),
            uvs: scene.uvs.clone(),
            culled: scene.clusters.as_ref().filter(|_| cull).map(|c| Culled {
                vertices: c.vertices.clone(),
                uvs: c.uvs.clone(),
                indices: c.indices.clone(),
                max_per_view: c.max_per_view.max(1),
                count_buffer: device.adapter.features.draw_indirect_count,
                tree: c.tree.clone(),
                cull_triangles: desc.cull_triangles,
                rd: desc.rd,
            }),
            device: device.clone(),
        }
    }

    /// `push` with how emitters are written.
    pub(super) fn push(&self, push: &SensorPush) -> SensorPush {
        SensorPush { exact: self.exact as u32, emission_scale: self.emission_scale, ..*push }
    }

    /// Bytes per sensor of `desc` of what draws it from clusters (none at full detail), for the batch size.
    pub(super) fn draw_bytes(&self, desc: &StrategyDesc) -> DrawBytes {
        let Some(c) = &self.culled else { return DrawBytes::default() };
        let views = desc.layout.views() as u64;
        let lists = views * (c.max_per_view as u64 * size_of::<GpuDrawCommand>() as u64 + c.tree.queue_bytes(1));
        let pool = views * 4 * region(c) as u64;
        DrawBytes { lists, pool, memory: lists + pool + views * (4 * c.max_per_view as u64 + 24) }
    }
}

/// A sensor pipeline: the render pass and the pipeline drawing the scene into sensor maps.
pub(super) struct SensorPipeline {
    // Field order is drop order.
    pub(super) pipeline: Pipeline,
    pub(super) layout: PipelineLayout,
    pub(super) render_pass: RenderPass,
    pub(super) inputs: SensorInputs,
}

impl SensorPipeline {
    /// `vertex`: the strategy's vertex shader, and its `TEXTURES` variant for a scene with textures or cut-outs;
    /// `view_mask` 0 for ordinary passes. `cull`: draw from the scene's clusters where it has them.
    pub(super) fn new(
        device: &Arc<Device>,
        scene: &GpuScene,
        desc: &StrategyDesc,
        (vertex, view_mask): ([&[u8]; 2], u32),
        cull: bool,
    ) -> Result<Self> {
        let render_pass = RenderPass::new(device, &[MAP_FORMAT], Some(DEPTH_FORMAT), view_mask)?;
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let (vertex_stage, fragment_stage) = (vk::ShaderStageFlags::VERTEX, vk::ShaderStageFlags::FRAGMENT);
        // Views and materials for both shaders, texture coordinates for the vertex shader, the radiance
        // cache and textures (the `TEXTURES` variant) for the fragment shader.
        let layout = PipelineLayout::new(
            device,
            &[
                (0, storage, vertex_stage | fragment_stage),
                (1, storage, vertex_stage | fragment_stage),
                (2, storage, fragment_stage),
                (3, storage, fragment_stage),
                (4, storage, fragment_stage),
                (5, storage, vertex_stage),
                (6, storage, fragment_stage),
                (7, storage, fragment_stage),
            ],
            size_of::<SensorPush>() as u32,
            vertex_stage | fragment_stage,
        )?;
        let inputs = SensorInputs::new(device, scene, desc, cull);
        // Drawn from per-view lists, a draw's view comes from the push constants (VIEW_PER_DRAW,
        // sensor_common.glsl).
        let view_per_draw = inputs.culled.is_some() as u32;
        let pipeline = Pipeline::graphics(
            device,
            &layout,
            &GraphicsDesc {
                vertex: vertex[scene.textured as usize],
                vertex_constants: &[view_per_draw],
                fragment: if scene.textured { shaders::SENSOR_FRAG_TEXTURES } else { shaders::SENSOR_FRAG },
                render_pass: render_pass.raw,
                color_attachments: 1,
                vertex_stride: VERTEX_STRIDE,
                vertex_attributes: &VERTEX_ATTRIBUTES,
                depth_compare: Some(DEPTH_COMPARE),
            },
        )?;
        Ok(Self { pipeline, layout, render_pass, inputs })
    }

    pub(super) fn draw_bytes(&self, desc: &StrategyDesc) -> DrawBytes {
        self.inputs.draw_bytes(desc)
    }

    /// Begins the render pass on `framebuffer` (over `area`, or all of it) and binds the pipeline, the
    /// slot's views and the scene.
    pub(super) fn begin<'e, 'a>(
        &self,
        enc: &'e Encoder<'a>,
        slot: &SlotMaps,
        framebuffer: &Framebuffer,
        ck: CkParams,
        area: Option<vk::Extent2D>,
    ) -> RenderPassScope<'e, 'a> {
        let pass = enc.begin_render_pass(&self.render_pass, framebuffer, &SlotMaps::clears(ck.background), area);
        pass.bind(&self.pipeline, &self.layout, slot.set);
        match &self.inputs.culled {
            Some(c) => {
                pass.bind_vertices(&c.vertices);
                pass.bind_indices(&c.indices);
            }
            None => pass.bind_vertices(&self.inputs.vertices),
        }
        pass
    }

    /// Draws views `first..first + count` of the slot (each into the layer or tile it names): one instanced
    /// draw of the whole scene, or, culled, each view's own draw list.
    pub(super) fn draw_views(
        &self,
        pass: &RenderPassScope<'_, '_>,
        slot: &SlotMaps,
        push: &SensorPush,
        (first, count): (u32, u32),
    ) {
        match &slot.draws {
            None => self.draw(pass, push, count, first),
            Some(d) => {
                let push = self.inputs.push(push);
                let stride = size_of::<GpuDrawCommand>() as u64;
                let views = first..first + count;
                // The triangle pass's survivors, each view's region of the pool, then the clusters it left
                // whole (none, mostly: each list's count is then 0, or without a count buffer its commands
                // draw nothing), from the clusters' indices.
                if d.region > 0 {
                    pass.bind_indices(&d.pool);
                    for v in views.clone() {
                        pass.push(&self.layout, &SensorPush { first_view: v, ..push });
                        // Counted where the lists are: lavapipe (Mesa 25.0) draws a plain indirect draw after a
                        // counted one with the counted one's count.
                        let counted = d.count_buffer.then_some((&d.region_draws, 4 * v as u64));
                        pass.draw_indexed_indirect(&d.regions, v as u64 * stride, counted, 1);
                    }
                    pass.bind_indices(self.inputs.culled.as_ref().map(|c| &*c.indices).expect("drawn from clusters"));
                }
                for v in views {
                    pass.push(&self.layout, &SensorPush { first_view: v, ..push });
                    let offset = v as u64 * d.max_per_view as u64 * stride;
                    let counted = d.count_buffer.then_some((&d.counts, 4 * v as u64));
                    pass.draw_indexed_indirect(&d.commands, offset, counted, d.max_per_view);
                }
            }
        }
    }

    /// Draws the scene `instances` times starting at view `first_instance`.
    pub(super) fn draw(&self, pass: &RenderPassScope<'_, '_>, push: &SensorPush, instances: u32, first_instance: u32) {
        let push = self.inputs.push(push);
        pass.push(&self.layout, &push);
        pass.draw(self.inputs.vertex_count, instances, 0, first_instance);
    }
}
