//! A lightmap baked (`sensorlight bake`, docs/DESIGN.md §14): the mesh unwrapped into an atlas, each
//! texel's surface point placed, every point sensed by the renderer as a pixel would be (after the radiance
//! cache), the gutter filled. The steps are the `lightmap` module's, on the CPU, and
//! [`Renderer::sense_points`], on the GPU; this joins them.

use anyhow::{Result, bail};
use glam::Vec3;

use rayon::prelude::*;

use crate::lightmap::Atlas;
use crate::lightmap::texels::{self, TexelPoint, Texels};
use crate::lightmap::unwrap::{self, Density, Unwrapped};
use crate::params::{Antialiasing, FrameParams};
use crate::renderer::{Progress, Renderer};
use crate::scene::Scene;
use crate::scene::bvh::Bvh;

/// Where the lightmap lies and which point each texel stands for: the bake's CPU part, before any sensing.
pub struct Layout {
    pub unwrapped: Unwrapped,
    pub texels: Texels,
}

impl Layout {
    /// Unwraps `scene`'s mesh at `density` into pages of at most `max_side` a side and places each texel's
    /// point (`bvh`: the mesh's, for the points inside geometry).
    pub fn new(scene: &Scene, bvh: &Bvh, density: Density, max_side: u32) -> Result<Self> {
        let unwrapped = unwrap::unwrap(&scene.mesh, density, max_side)?;
        let (bias, _) = crate::sensors::frame::offsets(scene.mesh.scale());
        let texels = Texels::rasterise(&scene.mesh, bvh, &unwrapped, bias);
        Ok(Self { unwrapped, texels })
    }
}

/// The light at every texel of `layout`, as `renderer` (built for `scene`) senses it with `frame`: each
/// texel's point, then, where a texel's light differs from a neighbour's by more than
/// [`texels::CONTRAST`], the mean over [`texels::FOOTPRINT`] points of its footprint (with `frame.aa`, as a
/// render supersamples its pixels where the light changes inside them); the gutter and the
/// buried texels filled from their neighbours. `bvh` is the scene's.
pub fn bake(
    renderer: &mut Renderer,
    (scene, bvh): (&Scene, &Bvh),
    layout: &Layout,
    frame: &FrameParams,
    progress: &dyn Progress,
) -> Result<Baked> {
    let mesh = &scene.mesh;
    // The second pass reads the cache the first solved.
    renderer.keep_cache();
    let (r, _) = renderer.sense_points(&layout.texels.gbuffer(mesh), frame, progress)?;
    let mut light: Vec<Vec3> = r.iter().map(|v| v.truncate()).collect();
    // With `--aa off`, the points alone.
    let contrasted = match frame.aa {
        Antialiasing::On => layout.texels.contrasted(&light),
        Antialiasing::Off => Vec::new(),
    };
    let footprints: Vec<Vec<TexelPoint>> =
        contrasted.par_iter().map(|&i| layout.texels.footprint(i, (mesh, bvh), &layout.unwrapped)).collect();
    let points: Vec<Option<TexelPoint>> = footprints.iter().flatten().map(|&p| Some(p)).collect();
    let r = match points.is_empty() {
        true => Vec::new(),
        false => renderer.sense_points(&texels::gbuffer(mesh, &points), frame, progress)?.0,
    };
    let mut k = 0;
    for (&i, footprint) in contrasted.iter().zip(&footprints) {
        if !footprint.is_empty() {
            light[i] = r[k..k + footprint.len()].iter().map(|v| v.truncate()).sum::<Vec3>() / footprint.len() as f32;
        }
        k += footprint.len();
    }
    if let Some(i) = light.iter().position(|v| !v.is_finite()) {
        bail!("the lightmap's texel {i} is not finite ({}): a bug; please report it", light[i]);
    }
    let valid = layout.texels.points.iter().map(Option::is_some).collect();
    let u = &layout.unwrapped;
    let mut atlas = Atlas::new((u.width, u.height, u.pages), light, valid);
    atlas.dilate();
    Ok(Baked { atlas, footprints: contrasted.len() as u64, footprint_points: points.len() as u64 })
}

/// A bake's result.
pub struct Baked {
    pub atlas: Atlas,
    /// Texels taken over their footprint, and the points sensed for them.
    pub footprints: u64,
    pub footprint_points: u64,
}
