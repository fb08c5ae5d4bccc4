//! The G-buffer on the host: what the camera sees through each pixel centre (paper §III-F). The GPU pass
//! `passes::gbuffer` and the CPU ray caster [`cast`] both fill it (the caster also at any image points: the
//! supersampling's sub-pixel samples, and the oracle's); the refinement, the CPU
//! reference and the outputs read it. It lives here, apart from both producers, so that CPU code never
//! depends on a GPU pass.

pub mod cast;

use glam::Vec4;

use crate::scene::{ImageSize, SurfaceId};

/// The G-buffer on the host, row-major from the top-left pixel.
#[derive(Clone, Debug)]
pub struct GBufferData {
    pub size: ImageSize,
    /// xyz world position; w = 1 where a surface is seen, 0 on the background.
    pub position: Vec<Vec4>,
    /// Unit normal turned towards the camera; w = 1 where the front side is seen.
    pub normal: Vec<Vec4>,
    pub albedo: Vec<Vec4>,
    /// `Ke` where an emitter's front side is seen, else 0.
    pub emission: Vec<Vec4>,
    /// Surface id; [`crate::scene::NO_SURFACE`] on the background.
    pub surface: Vec<SurfaceId>,
}
