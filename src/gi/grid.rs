//! The world-space grid the radiance cache is keyed on, and the key and hash that `glsl/cache.glsl` computes
//! bit for bit the same way (u32 arithmetic, one f32 multiply per axis).
//!
//! A key is a cell and a surface id: two surfaces in one cell (a wall and the floor meeting it, a box on the
//! floor) are different pieces, and each side of a piece a different entry, so light never crosses from one
//! surface to another, or from one side of a thin wall to the other, through a cell.
//!
//! ```text
//!   key[0] = cx | cy << 10 | cz << 20        (cells 0..1023 along each axis)
//!   key[1] = surface                           (≥ 1: 0 marks an empty slot)
//! ```

use glam::{IVec3, UVec3, Vec3};

use crate::scene::{Aabb, SurfaceId};

/// Cells along an axis at most (10 bits of the key).
pub const MAX_CELLS: u32 = 1023;
const _: () = assert!(crate::params::MAX_CACHE_RESOLUTION == MAX_CELLS - 1, "the resolution a user may ask fits");

/// Where the grid's corner sits below the scene's box, in cells: an offset no shipped scene's walls share,
/// so that axis-aligned walls at round coordinates do not lie on cell boundaries (where rounding would put
/// their fragments on either side).
const CORNER_OFFSET: Vec3 = Vec3::new(0.302_79, 0.271_83, 0.414_21);

/// Cells of side `cell` from `origin`, `dims` along each axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub origin: Vec3,
    pub cell: f32,
    /// `1 / cell`, as the shader multiplies by it (the same f32, so the same cells).
    pub inv_cell: f32,
    pub dims: UVec3,
}

impl Grid {
    /// `resolution` cells along the longest side of `bounds` (clamped to 1..[`MAX_CELLS`] − 1, so that
    /// the corner offset fits).
    pub fn new(bounds: Aabb, resolution: u32) -> Self {
        let extent = (bounds.max - bounds.min).max(Vec3::splat(f32::MIN_POSITIVE));
        let resolution = resolution.clamp(1, MAX_CELLS - 1);
        let cell = extent.max_element() / resolution as f32;
        let origin = bounds.min - CORNER_OFFSET * cell;
        let inv_cell = 1.0 / cell;
        let dims = ((bounds.max - origin) * inv_cell).floor().as_uvec3() + UVec3::ONE;
        Self { origin, cell, inv_cell, dims: dims.min(UVec3::splat(MAX_CELLS)) }
    }

    /// The cell holding `p`, clamped into the grid.
    pub fn cell_of(&self, p: Vec3) -> UVec3 {
        let c = ((p - self.origin) * self.inv_cell).floor().as_ivec3();
        c.clamp(IVec3::ZERO, self.dims.as_ivec3() - IVec3::ONE).as_uvec3()
    }

    /// The box of cell `c`.
    pub fn cell_box(&self, c: UVec3) -> Aabb {
        let min = self.origin + c.as_vec3() * self.cell;
        Aabb { min, max: min + Vec3::splat(self.cell) }
    }
}

/// A cache key: a cell and a surface.
pub fn key(cell: UVec3, surface: SurfaceId) -> [u32; 2] {
    [cell.x | cell.y << 10 | cell.z << 20, surface]
}

/// The table's hash of a key (a 32-bit avalanche mix of both words; `glsl/cache.glsl` `cache_hash`).
pub fn hash(key: [u32; 2]) -> u32 {
    let mut h = key[0].wrapping_mul(0x9e37_79b1) ^ key[1].wrapping_mul(0x85eb_ca77);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^ (h >> 16)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_covers_the_box_with_its_corner_offset() {
        let bounds = Aabb { min: Vec3::ZERO, max: Vec3::new(556.0, 548.8, 559.2) };
        let g = Grid::new(bounds, 16);
        assert_eq!(g.cell, 559.2 / 16.0);
        assert!(g.cell_box(UVec3::ZERO).min.cmplt(bounds.min).all());
        assert!(g.cell_box(g.dims - UVec3::ONE).max.cmpgt(bounds.max).all());
        assert_eq!(g.cell_of(bounds.min), UVec3::ZERO);
        assert_eq!(g.cell_of(Vec3::splat(-1e9)), UVec3::ZERO, "clamped");
        assert_eq!(g.cell_of(Vec3::splat(1e9)), g.dims - UVec3::ONE, "clamped");
        // A wall at a round coordinate is well inside a cell.
        let x = (278.0 - g.origin.x) * g.inv_cell;
        assert!((x - x.round()).abs() > 0.1, "{x}");
    }

    #[test]
    fn keys_separate_cells_and_surfaces() {
        let k = key(UVec3::new(1, 2, 3), 7);
        assert_eq!(k, [1 | 2 << 10 | 3 << 20, 7]);
        assert_ne!(hash(k), hash(key(UVec3::new(1, 2, 3), 6)));
        assert_ne!(hash(k), hash(key(UVec3::new(1, 3, 2), 7)));
    }
}
