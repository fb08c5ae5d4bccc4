//! Global illumination: a view-independent radiance cache (docs/DESIGN.md §10).
//!
//! The sensors measure the light arriving at a point; what global illumination needs besides is the light
//! *leaving* every other surface, those the camera does not see included. The cache holds it: the reflected
//! radiance `Kd·R` of each side of each surface within each cell of a world-space grid ([`grid`]), sensed by
//! a sensor at one point of that piece ([`entries`]) with the renderer's own batches, strategies and exact
//! direct estimator, and iterated bounce by bounce ([`solve`]). The sensor maps then see, on every surface,
//! the cache's value instead of the paper's `Kd·ε` (`glsl/cache.glsl`), and the camera's sensors gather it:
//! the cache may be coarse, since contact shadows and fine indirect detail come from the gather.
//!
//! Why a hashed grid keyed by (cell, surface, side), and not lightmap texels: it needs no parameterisation
//! of the mesh, so any level of detail of a large mesh looks it up by position (texels would belong to one
//! level's triangles); its size follows the scene's area over the cell size, not the triangle count; and
//! keying by surface and side keeps the two sides of a thin wall, and a wall and the floor it stands on,
//! apart, which is where grids leak light.

pub mod entries;
pub mod file;
pub mod grid;
pub mod piece_mean;
pub mod polygon;
pub mod reach;
pub mod shape;
pub mod solve;
pub mod transport;

use glam::{Vec3, Vec4};

use crate::gpu_types::{GpuCacheGrid, GpuCacheSlot, GpuCacheSplit};
use crate::scene::{Mesh, SurfaceId};
pub use entries::{Entry, LightVaries, SPLIT, Split};
pub use grid::Grid;

/// The highest reflectance the bounces use: at 1 a closed room would reflect its light forever (the series
/// diverges). Materials above it are clamped for the cache only, and said so once ([`albedo_warnings`]).
pub const MAX_ALBEDO: f32 = 0.98;

/// What global illumination says of `mesh` before it renders: each material in use whose surfaces reflect
/// more than [`MAX_ALBEDO`] (`Kd`, times its texture's mean where it has one: `Mesh::surface_albedo`), once.
/// A textured material's `Kd` of 1 (the usual way to say "the texture's colour") is not such a one.
pub fn albedo_warnings(mesh: &Mesh) -> Vec<String> {
    let mut brightest: Vec<Option<Vec3>> = vec![None; mesh.materials.len()];
    for id in 1..=mesh.surfaces.len() as SurfaceId {
        let (m, albedo) = (mesh.surfaces[id as usize - 1].material, mesh.surface_albedo(id));
        brightest[m] = Some(brightest[m].map_or(albedo, |b| b.max(albedo)));
    }
    (mesh.materials.iter().zip(brightest))
        .filter_map(|(m, albedo)| albedo.filter(|a| a.max_element() > MAX_ALBEDO).map(|a| (m, a)))
        .map(|(m, a)| {
            let albedo = m.format.albedo_word();
            let what =
                if a == m.kd { format!("has {albedo}") } else { format!("reflects ({albedo} × its texture's mean)") };
            format!(
                "material '{}' {what} {} {} {}: global illumination's bounces use at most {MAX_ALBEDO} per channel \
                 (at 1 a closed room would reflect its light forever)",
                m.name, a.x, a.y, a.z
            )
        })
        .collect()
}

/// How far towards the eye a fragment is moved to be tested against split planes, relative to its distance
/// (`glsl/cache.glsl` `CACHE_SPLIT_PULL`).
pub const SPLIT_PULL: f32 = 1e-3;

/// The cache's points and the table that finds them.
pub struct RadianceCache {
    /// Cells along the scene's longest side.
    pub resolution: u32,
    pub grid: Grid,
    /// Two per piece of surface in a cell (or part of a split piece): its back, then its front.
    pub entries: Vec<Entry>,
    /// The planes that split pieces (see [`entries`]).
    pub splits: Vec<Split>,
    /// Each entry's reflectance (its surface's `Kd`, at most [`MAX_ALBEDO`]).
    pub albedo: Vec<Vec3>,
    /// The open-addressing table over every key (a power of two of slots, at most half full).
    pub slots: Vec<GpuCacheSlot>,
    /// Keys in the table: (cell, surface) pairs, their aliases included.
    pub keys: usize,
    /// Splits that halve a piece where its direct light varies.
    pub light_splits: usize,
    /// Entry pairs whose direct light is the mean over the points spread over their piece, `points` (see
    /// [`entries`]).
    pub spread: Vec<u32>,
    /// Per entry pair, points spread over its piece with their front normals ([`piece_mean`]).
    pub points: Vec<[(Vec3, Vec3); entries::SAMPLES_PER_PIECE]>,
    /// Entries whose side of their piece lies inside a closed shape: never sensed, dark (see [`entries`]).
    pub buried: Vec<u32>,
    /// Surface ids run 1..=surfaces; each side of each has a fallback value after the entries.
    pub surfaces: u32,
}

impl RadianceCache {
    /// The cache of `mesh` with `resolution` cells along its longest side; `lod`: triangles of coarser levels
    /// of detail the sensor maps may draw instead of the mesh's; `light`: where the direct light varies,
    /// pieces are halved; `offsets`: the sensors' lift and near plane (`sensors::frame::offsets`), which keep
    /// them out of closed shapes (see [`entries`]). Distant lights (the sun) have no entries: they reflect
    /// nothing, and lie outside the grid.
    pub fn build(
        mesh: &Mesh,
        resolution: u32,
        lod: &[([Vec3; 3], SurfaceId)],
        light: Option<LightVaries<'_>>,
        offsets: (f32, f32),
    ) -> Self {
        let grid = Grid::new(mesh.bounds, resolution);
        let local = mesh.local_triangles();
        let last_local = local.iter().map(|t| t.surface).max().unwrap_or(0);
        let local_lod: Vec<([Vec3; 3], SurfaceId)> = lod.iter().filter(|(_, s)| *s <= last_local).copied().collect();
        let corrugated = shape::corrugated(mesh, local, grid.cell);
        let pieces = entries::build(&grid, local, &local_lod, (light, &corrugated), offsets);
        let albedo =
            pieces.entries.iter().map(|e| mesh.surface_albedo(e.surface).min(Vec3::splat(MAX_ALBEDO))).collect();
        let keys: Vec<([u32; 2], u32)> =
            pieces.keys.iter().map(|&((cell, surface), reference)| ([cell, surface], reference)).collect();
        let slots = table(&keys);
        Self {
            resolution,
            grid,
            entries: pieces.entries,
            splits: pieces.splits,
            albedo,
            slots,
            keys: keys.len(),
            light_splits: pieces.light_splits,
            spread: pieces.spread,
            points: pieces.points,
            buried: pieces.buried,
            surfaces: mesh.surfaces.len() as u32,
        }
    }

    /// The grid as the shader reads it, at the head of the table buffer.
    pub fn gpu_grid(&self) -> GpuCacheGrid {
        GpuCacheGrid {
            origin: self.grid.origin.extend(self.grid.inv_cell),
            dims: [self.grid.dims.x, self.grid.dims.y, self.grid.dims.z, self.slots.len() as u32 - 1],
            entries: self.entries.len() as u32,
            _pad: [0; 3],
        }
    }

    /// Values of the values buffer: `values` (one per entry), then each surface side's fallback.
    pub fn values_len(&self) -> usize {
        self.entries.len() + 2 * (self.surfaces as usize + 1)
    }

    /// The values buffer for reflected radiance `values` per entry: each followed, for a fragment no key
    /// finds (none should), by its surface side's area-weighted mean.
    pub fn gpu_values(&self, values: &[Vec3]) -> Vec<Vec4> {
        let mut sums = vec![(Vec3::ZERO, 0.0f32); 2 * (self.surfaces as usize + 1)];
        for (e, v) in self.entries.iter().zip(values) {
            let s = &mut sums[2 * e.surface as usize + e.front as usize];
            s.0 += *v * e.area;
            s.1 += e.area;
        }
        let fallback = sums.iter().map(|(v, a)| if *a > 0.0 { *v / *a } else { Vec3::ZERO });
        values.iter().copied().chain(fallback).map(|v| v.extend(0.0)).collect()
    }

    /// The value index a fragment at `p` on `surface`'s `front` (or back) reads, seen from far along its
    /// side's normal: the CPU twin of `cache_lookup` in `glsl/cache.glsl` (see [`Self::lookup_from`]).
    pub fn lookup(&self, p: Vec3, surface: SurfaceId, front: bool) -> usize {
        self.lookup_from(p, p, surface, front)
    }

    /// The value index a fragment at `p` on `surface`'s `front` (or back) reads seen from `eye`: split
    /// planes are tested [`SPLIT_PULL`] of the way from `p` to `eye`, so that a fragment on a seam, a
    /// rounding error past a wall, is read on the side it is seen from.
    pub fn lookup_from(&self, p: Vec3, eye: Vec3, surface: SurfaceId, front: bool) -> usize {
        let key = grid::key(self.grid.cell_of(p), surface);
        let mask = self.slots.len() - 1;
        let mut i = grid::hash(key) as usize & mask;
        let mut reference = loop {
            let slot = &self.slots[i];
            if slot.key[1] == 0 {
                return self.entries.len() + 2 * surface as usize + front as usize;
            }
            if slot.key == key {
                break slot.entry;
            }
            i = (i + 1) & mask;
        };
        let q = p.lerp(eye, SPLIT_PULL);
        while reference & SPLIT != 0 {
            let split = &self.splits[(reference & !SPLIT) as usize];
            reference = split.children[(split.plane.truncate().dot(q) + split.plane.w >= 0.0) as usize];
        }
        2 * reference as usize + front as usize
    }

    /// The splits as the shader reads them (one unused entry where there are none: buffers are never
    /// empty).
    pub fn gpu_splits(&self) -> Vec<GpuCacheSplit> {
        let splits = self.splits.iter().map(|s| GpuCacheSplit { plane: s.plane, children: s.children, _pad: [0; 2] });
        let all: Vec<GpuCacheSplit> = splits.collect();
        if all.is_empty() { vec![GpuCacheSplit::default()] } else { all }
    }

    /// At least how many bytes on the GPU the cache of `mesh` at `resolution` will take, before it is built:
    /// every triangle's area in cells, and at least one cell per triangle, a pair of entries each. The
    /// mesh's own triangles only, as the cache holds: a sun's disc, far away and hundreds of metres wide,
    /// counted as millions of cells, refused a 0.6° sun.
    pub fn bytes_at_least(mesh: &Mesh, resolution: u32) -> u64 {
        let cell = Grid::new(mesh.bounds, resolution).cell as f64;
        let cells: f64 = mesh
            .local_triangles()
            .iter()
            .map(|t| (crate::scene::triangle_area(&t.v) as f64 / (cell * cell)).max(1.0))
            .sum();
        // A value per entry, two table slots per key (at most half full).
        (cells * (2.0 * 16.0 + 2.0 * size_of::<GpuCacheSlot>() as f64) / 2.0) as u64
    }

    /// Bytes on the GPU: the table and the values.
    pub fn bytes(&self) -> u64 {
        (size_of::<GpuCacheGrid>()
            + self.slots.len() * size_of::<GpuCacheSlot>()
            + self.splits.len() * size_of::<GpuCacheSplit>()
            + self.values_len() * 16) as u64
    }
}

/// Linear probing over `keys` (inserted in order, so the table is the same on every run).
fn table(keys: &[([u32; 2], u32)]) -> Vec<GpuCacheSlot> {
    let size = (2 * keys.len()).next_power_of_two().max(16);
    let mask = size - 1;
    let mut slots = vec![GpuCacheSlot::default(); size];
    for &(key, entry) in keys {
        let mut i = grid::hash(key) as usize & mask;
        while slots[i].key[1] != 0 {
            i = (i + 1) & mask;
        }
        slots[i] = GpuCacheSlot { key, entry, _pad: 0 };
    }
    slots
}
