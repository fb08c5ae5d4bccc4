//! The scene as the GPU passes read it: a vertex buffer (triangle soup), per-triangle normals and the
//! per-surface materials. Uploaded once per renderer and shared (hence `Arc`) by the G-buffer and sensor
//! passes, each of which keeps what it draws with alive. A large mesh also gets its cluster hierarchy
//! ([`GpuClusters`], docs/DESIGN.md §9), which the sensor maps draw from after the culling pass.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use glam::{Vec2, Vec3, Vec4};

use crate::clusters::{ClusterMesh, CullTree, ErrorBounds, max_selected};
use crate::gi::RadianceCache;
use crate::gpu_types::{
    CLUSTER_CLOSED, CLUSTER_EMITTER, EMITTER_CHUNK, GpuCacheGrid, GpuCacheSlot, GpuCacheSplit, GpuCluster, GpuCullNode,
    GpuEmitter, GpuEmitterChunk, GpuLightGroup, GpuSky, GpuSurface, GpuTexture, MAX_GROUPS, NODE_LEAF, Vertex,
};
use crate::light::groups::{self, Lights};
use crate::scene::{Aabb, Mesh, Scene, SkyMap, Texture};
use crate::vk::{Buffer, Device, transfer};

pub struct GpuScene {
    pub vertices: Arc<Buffer>,
    pub vertex_count: u32,
    /// One `vec4` per vertex of the soup: its triangle's shading normal at that corner (the front normal on
    /// a flat mesh), which the G-buffer interpolates.
    pub normals: Arc<Buffer>,
    /// One `vec2` per vertex of the soup: its texture coordinates ((0, 0) without textures).
    pub uvs: Arc<Buffer>,
    /// The colour textures: a `GpuTexture` each, and every level's packed texels (`scene::texture`).
    pub textures: Arc<Buffer>,
    pub texels: Arc<Buffer>,
    /// The sky map: its `GpuSky` (levels 0: no map, and one texel no shader reads) and its levels'
    /// linear texels (`vec4`, `scene::sky`).
    pub sky: Arc<Buffer>,
    pub sky_texels: Arc<Buffer>,
    /// Whether a surface has a texture or a cut-out: the sensor maps then read them (the `TEXTURES`
    /// variants of their shaders).
    pub textured: bool,
    /// `GpuSurface` per surface id (entry 0 unused).
    pub surfaces: Arc<Buffer>,
    /// The emitters, group by group (`GpuEmitter`); them in chunks of at most `EMITTER_CHUNK`
    /// (`GpuEmitterChunk`), and each group's range of chunks (`GpuLightGroup`).
    pub emitters: Arc<Buffer>,
    pub chunks: Arc<Buffer>,
    pub chunk_count: u32,
    pub groups: Arc<Buffer>,
    /// The same on the host: sensors' zoom views bound the groups.
    pub lights: Lights,
    /// The cluster hierarchy, when the scene is drawn from it.
    pub clusters: Option<GpuClusters>,
    /// The radiance cache the sensor maps read with global illumination.
    pub cache: GpuCache,
}

/// The radiance cache on the GPU (docs/DESIGN.md §10): the table the sensor maps' fragment shader looks keys
/// up in (`glsl/cache.glsl`), and the values it reads, which the renderer writes between bounces (no batch
/// in flight). Without global illumination an empty table that no shader reads (their push says so), so that
/// every pipeline binds the same.
pub struct GpuCache {
    /// `GpuCacheGrid`, then its `GpuCacheSlot`s.
    pub table: Arc<Buffer>,
    /// `vec4` per entry, then a fallback per surface side.
    pub values: Arc<Buffer>,
    /// `GpuCacheSplit`s: the planes that cut pieces.
    pub splits: Arc<Buffer>,
}

impl GpuCache {
    pub fn upload(device: &Arc<Device>, cache: Option<&RadianceCache>, surfaces: usize) -> Result<Self> {
        let (head, slots, splits, values) = match cache {
            Some(c) => (c.gpu_grid(), c.slots.clone(), c.gpu_splits(), c.values_len()),
            None => {
                let empty = vec![GpuCacheSlot::default(); 16];
                let head = GpuCacheGrid { dims: [1, 1, 1, empty.len() as u32 - 1], ..Default::default() };
                (head, empty, vec![GpuCacheSplit::default()], 2 * (surfaces + 1))
            }
        };
        let mut table: Vec<u8> = bytemuck::bytes_of(&head).to_vec();
        table.extend_from_slice(bytemuck::cast_slice(&slots));
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            table: Arc::new(transfer::upload(device, "radiance cache table", &table, storage)?),
            // Read back by `Renderer::cache_values`.
            values: Arc::new(transfer::upload(
                device,
                "radiance cache values",
                &vec![Vec4::ZERO; values],
                storage | vk::BufferUsageFlags::TRANSFER_SRC,
            )?),
            splits: Arc::new(transfer::upload(device, "radiance cache splits", &splits, storage)?),
        })
    }
}

/// A mesh's cluster hierarchy on the GPU: its own (welded) vertices, the triangles of every level as
/// indices, and the clusters as the culling pass reads them.
pub struct GpuClusters {
    pub vertices: Arc<Buffer>,
    /// Their texture coordinates where the mesh has textures or cut-outs (else a placeholder no shader reads).
    pub uvs: Arc<Buffer>,
    pub indices: Arc<Buffer>,
    /// `GpuCluster` each.
    pub clusters: Arc<Buffer>,
    pub count: u32,
    /// Their bounding tree (`clusters::CullTree`): `GpuCullNode`s, the leaves' cluster indices, and its
    /// shape, which the culling pass walks.
    pub nodes: Arc<Buffer>,
    pub items: Arc<Buffer>,
    pub tree: TreeShape,
    /// No view selects more clusters than this (`clusters::max_selected`): the draw slots per view.
    pub max_per_view: u32,
    /// Triangles of the mesh itself (the finest level).
    pub full_detail_triangles: u64,
}

impl GpuClusters {
    pub fn upload(device: &Arc<Device>, mesh: &Mesh, hierarchy: &ClusterMesh) -> Result<Self> {
        let emitter = |s| mesh.material_of(s).is_emitter();
        let clusters = gpu_clusters(hierarchy, emitter);
        let tree = CullTree::build(hierarchy, emitter);
        let vertices: Vec<Vertex> = hierarchy
            .positions
            .iter()
            .zip(&hierarchy.vertex_surface)
            .map(|(&position, &surface)| Vertex { position, surface })
            .collect();
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let uvs = if mesh.has_textures() { cluster_uvs(mesh, hierarchy) } else { vec![Vec2::ZERO] };
        Ok(Self {
            uvs: Arc::new(transfer::upload(device, "cluster texture coordinates", &uvs, storage)?),
            vertices: Arc::new(transfer::upload(
                device,
                "cluster vertices",
                &vertices,
                vk::BufferUsageFlags::VERTEX_BUFFER | storage, // storage: the compute strategy reads them
            )?),
            indices: Arc::new(transfer::upload(
                device,
                "cluster indices",
                &hierarchy.indices,
                vk::BufferUsageFlags::INDEX_BUFFER | storage,
            )?),
            clusters: Arc::new(transfer::upload(device, "clusters", &clusters, storage)?),
            count: clusters.len() as u32,
            nodes: Arc::new(transfer::upload(device, "cluster tree", &gpu_cull_nodes(&tree), storage)?),
            items: Arc::new(transfer::upload(device, "cluster tree leaves", &tree.items, storage)?),
            tree: TreeShape { root: tree.root, per_depth: tree.per_depth.clone() },
            max_per_view: max_selected(hierarchy) as u32,
            full_detail_triangles: hierarchy.full_detail_triangles() as u64,
        })
    }
}

/// The texture coordinates of each of the hierarchy's vertices: those of a corner of the mesh's at the
/// same position on the same surface. Welding and simplifying keep the mesh's own vertices, so every one has
/// such a corner; where a surface's texture has a seam there, the first corner's.
pub fn cluster_uvs(mesh: &Mesh, hierarchy: &ClusterMesh) -> Vec<Vec2> {
    let key = |p: Vec3, surface: u32| (p.to_array().map(f32::to_bits), surface);
    let mut corners = std::collections::HashMap::new();
    for (t, uvs) in mesh.triangles.iter().zip(&mesh.uvs) {
        for (p, uv) in t.v.iter().zip(uvs) {
            corners.entry(key(*p, t.surface)).or_insert(*uv);
        }
    }
    (hierarchy.positions.iter().zip(&hierarchy.vertex_surface))
        .map(|(&p, &s)| corners.get(&key(Vec3::from(p), s)).copied().unwrap_or(Vec2::ZERO))
        .collect()
}

/// The clusters as the culling pass reads them; `emitter(surface)` says which surfaces emit.
pub fn gpu_clusters(clusters: &ClusterMesh, emitter: impl Fn(u32) -> bool) -> Vec<GpuCluster> {
    clusters
        .clusters
        .iter()
        .map(|k| {
            let ([own_min, own_max], [parent_min, parent_max]) = (gpu_bounds(&k.own), gpu_bounds(&k.parent));
            let corners =
                Aabb::of(clusters.triangles_of(k).flatten().map(|v| Vec3::from(clusters.positions[v as usize])));
            GpuCluster {
                sphere: Vec4::from(k.sphere),
                slab: Vec4::from(k.slab),
                box_min: corners.min.extend(0.0),
                box_max: corners.max.extend(0.0),
                own_min,
                own_max,
                parent_min,
                parent_max,
                first_index: k.first_index,
                index_count: k.index_count,
                flags: if emitter(k.surface) { CLUSTER_EMITTER } else { 0 }
                    | if k.closed != 0 { CLUSTER_CLOSED } else { 0 },
                _pad: 0,
                part_min: Vec3::from(k.part_min).extend(0.0),
                part_max: Vec3::from(k.part_max).extend(0.0),
            }
        })
        .collect()
}

/// Error bounds as the culling pass reads them: the box's corners, the error in the first's w.
pub fn gpu_bounds(b: &ErrorBounds) -> [Vec4; 2] {
    [Vec3::from(b.min).extend(b.error), Vec3::from(b.max).extend(0.0)]
}

/// The error bounds that [`gpu_bounds`] wrote as `[min, max]`.
pub fn bounds_from_gpu(min: Vec4, max: Vec4) -> ErrorBounds {
    ErrorBounds { min: min.truncate().into(), max: max.truncate().into(), error: min.w }
}

/// The shape of the tree walked: its root and how many nodes lie at each depth.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeShape {
    pub root: u32,
    pub per_depth: Vec<u32>,
}

impl TreeShape {
    /// Bytes of queue the culling pass's walk needs for a batch of `views` views: a (node, view) pair of
    /// 8 bytes for each view and node below the root (each is queued at most once).
    pub fn queue_bytes(&self, views: u64) -> u64 {
        (8 * views * self.per_depth.iter().skip(1).map(|&n| n as u64).sum::<u64>()).max(8)
    }

    /// Bytes of the walk's counts: a `uvec4` per depth.
    pub fn walk_bytes(&self) -> u64 {
        16 * self.per_depth.len() as u64
    }
}

/// The clusters' bounding tree as the culling pass reads it.
pub fn gpu_cull_nodes(tree: &CullTree) -> Vec<GpuCullNode> {
    tree.nodes
        .iter()
        .map(|n| {
            let ([own_min, own_max], [parent_min, parent_max]) = (gpu_bounds(&n.own), gpu_bounds(&n.parent));
            GpuCullNode {
                sphere: Vec4::from(n.sphere),
                own_min,
                own_max,
                parent_min,
                parent_max,
                first: n.first,
                count: n.count,
                flags: if n.emitter { CLUSTER_EMITTER } else { 0 } | if n.leaf { NODE_LEAF } else { 0 },
                _pad: 0,
            }
        })
        .collect()
}

impl GpuScene {
    /// The scene, drawn at full detail (the G-buffer always is), and from `hierarchy` if given; `cache`: the
    /// radiance cache's table, with global illumination.
    pub fn upload(
        device: &Arc<Device>,
        scene: &Scene,
        hierarchy: Option<&ClusterMesh>,
        cache: Option<&RadianceCache>,
    ) -> Result<Self> {
        let mesh = &scene.mesh;
        let vertices = vertices(mesh);
        let lights = Lights::new(mesh);
        const _: () = assert!(groups::MAX_GROUPS == MAX_GROUPS, "the shaders' group count is the light module's");
        let emitters: Vec<GpuEmitter> = lights
            .emitters
            .iter()
            .map(|e| GpuEmitter {
                v0: e.v[0].extend(0.0),
                v1: e.v[1].extend(0.0),
                v2: e.v[2].extend(0.0),
                ke: e.ke.extend(0.0),
            })
            .collect();
        let mut chunks = Vec::new();
        let mut groups = Vec::new();
        for (g, group) in lights.groups.iter().enumerate() {
            let first_chunk = chunks.len() as u32;
            for first in group.emitters.clone().step_by(EMITTER_CHUNK as usize) {
                let count = EMITTER_CHUNK.min(group.emitters.end - first);
                chunks.push(GpuEmitterChunk { first, count, group: g as u32, _pad: 0 });
            }
            groups.push(GpuLightGroup { first_chunk, chunks: chunks.len() as u32 - first_chunk, _pad: [0; 2] });
        }
        let normals: Vec<Vec4> = mesh.corner_normals().map(|n| n.extend(0.0)).collect();
        // Without textures, placeholders that no shader reads (no surface names a texture).
        let uvs: Vec<Vec2> = if mesh.uvs.is_empty() { vec![Vec2::ZERO] } else { mesh.corner_uvs().collect() };
        let (mut texels, mut textures) = gpu_textures(&mesh.textures);
        if textures.is_empty() {
            (texels, textures) = (vec![0], vec![GpuTexture::default()]);
        }
        let (sky, sky_texels) = gpu_sky(scene.sky.as_deref());
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            vertex_count: vertices.len() as u32,
            vertices: Arc::new(transfer::upload(
                device,
                "vertices",
                &vertices,
                vk::BufferUsageFlags::VERTEX_BUFFER | storage,
            )?),
            normals: Arc::new(transfer::upload(device, "corner normals", &normals, storage)?),
            uvs: Arc::new(transfer::upload(device, "corner texture coordinates", &uvs, storage)?),
            textures: Arc::new(transfer::upload(device, "texture table", &textures, storage)?),
            texels: Arc::new(transfer::upload(device, "texels", &texels, storage)?),
            sky: Arc::new(transfer::upload(device, "sky map table", &[sky], storage)?),
            sky_texels: Arc::new(transfer::upload(device, "sky map texels", &sky_texels, storage)?),
            textured: mesh.has_textures(),
            surfaces: Arc::new(transfer::upload(device, "surfaces", &surfaces(mesh, &lights), storage)?),
            emitters: Arc::new(transfer::upload(device, "emitters", &emitters, storage)?),
            chunk_count: chunks.len() as u32,
            chunks: Arc::new(transfer::upload(device, "emitter chunks", &chunks, storage)?),
            groups: Arc::new(transfer::upload(device, "light groups", &groups, storage)?),
            lights,
            clusters: hierarchy.map(|h| GpuClusters::upload(device, mesh, h)).transpose()?,
            cache: GpuCache::upload(device, cache, mesh.surfaces.len())?,
        })
    }
}

/// The triangle soup: three vertices per triangle, each carrying its triangle's surface id.
pub fn vertices(mesh: &Mesh) -> Vec<Vertex> {
    mesh.triangles.iter().flat_map(|t| t.v.map(|p| Vertex { position: p.to_array(), surface: t.surface })).collect()
}

/// The material table indexed by surface id (entry 0: no surface); an emitter's `ke.w` is its group + 1.
pub fn surfaces(mesh: &Mesh, lights: &Lights) -> Vec<GpuSurface> {
    std::iter::once(GpuSurface::default())
        .chain((1..=mesh.surfaces.len() as u32).map(|id| {
            let m = mesh.material_of(id);
            let group = lights.surface_group.get(&id).map_or(0.0, |&g| g as f32 + 1.0);
            // A texture applies where the mesh has texture coordinates.
            let placed = !mesh.uvs.is_empty();
            let index = |map: Option<usize>| map.filter(|_| placed).map_or(0, |t| t as u32 + 1);
            let cutout = m.cutout.filter(|_| placed);
            GpuSurface {
                kd: mesh.surface_albedo(id).extend(0.0),
                ke: m.ke.extend(group),
                kd_factor: m.kd.extend(0.0),
                kd_map: index(m.kd_map),
                ke_map: index(m.ke_map),
                alpha_map: cutout.map_or(0, |c| c.map as u32 + 1),
                alpha_threshold: cutout.map_or(0.0, |c| c.threshold),
            }
        }))
        .collect()
}

/// Every texture's levels in one buffer, and where each texture lies in it (`scene::texture` draws the
/// layout).
pub fn gpu_textures(textures: &[Texture]) -> (Vec<u32>, Vec<GpuTexture>) {
    let mut texels = Vec::with_capacity(textures.iter().map(Texture::texel_count).sum());
    let table = textures
        .iter()
        .map(|t| {
            let offset = texels.len() as u32;
            t.levels.iter().for_each(|l| texels.extend_from_slice(&l.texels));
            GpuTexture { offset, width: t.width(), height: t.height(), levels: t.levels.len() as u32 }
        })
        .collect();
    (texels, table)
}

/// The sky map's description and every level's texels, level 0 first (`scene::sky`); without a map, levels
/// 0 and one black texel.
pub fn gpu_sky(sky: Option<&SkyMap>) -> (GpuSky, Vec<Vec4>) {
    let Some(sky) = sky else { return (GpuSky::default(), vec![Vec4::ZERO]) };
    let texels = sky.levels.iter().flat_map(|l| l.texels.iter().map(|t| t.extend(0.0))).collect();
    let (sin, cos) = sky.rotation_deg.to_radians().sin_cos();
    let levels = sky.levels.len() as u32;
    let rotation = Vec4::new(cos, sin, 0.0, 0.0);
    (GpuSky { width: sky.width(), height: sky.height(), levels, _pad: 0, rotation }, texels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::texture::{Level, gpu_bytes};

    #[test]
    fn the_texture_table_points_at_each_textures_levels() {
        let level = |side: u32, texel: [u8; 4]| Level {
            width: side,
            height: side,
            texels: vec![u32::from_le_bytes(texel); (side * side) as usize],
        };
        let a = Texture::from_level("a", level(2, [1, 2, 3, 4]));
        let b = Texture::from_level("b", level(1, [5, 6, 7, 8]));
        let (texels, table) = gpu_textures(&[a.clone(), b]);
        assert_eq!(texels.len(), 4 + 1 + 1);
        assert_eq!((table[0].offset, table[0].levels), (0, 2));
        assert_eq!((table[1].offset, table[1].width, table[1].levels), (5, 1, 1));
        assert_eq!(texels[5], u32::from_le_bytes([5, 6, 7, 8]));
        assert_eq!(gpu_bytes(&[a]), 20);
    }
}
