//! A lightmap baked (`sensorlight bake`, docs/DESIGN.md §14): the mesh unwrapped into an atlas, each
//! texel's surface point placed, every point sensed by the renderer as a pixel would be (after the radiance
//! cache), the gutter filled. The steps are the `lightmap` module's, on the CPU, and
//! [`Renderer::sense_points`], on the GPU; this joins them.

use anyhow::{Result, bail};
use glam::Vec3;

use crate::lightmap::Atlas;
use crate::lightmap::texels::Texels;
use crate::lightmap::unwrap::{self, Density, Unwrapped};
use crate::params::FrameParams;
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

/// The light at every texel of `layout`, as `renderer` (built for `scene`) senses it with `frame`, the
/// gutter and the buried texels filled from their neighbours.
pub fn bake(
    renderer: &mut Renderer,
    scene: &Scene,
    layout: &Layout,
    frame: &FrameParams,
    progress: &dyn Progress,
) -> Result<Atlas> {
    let g = layout.texels.gbuffer(&scene.mesh);
    let (r, _) = renderer.sense_points(&g, frame, progress)?;
    let light: Vec<Vec3> = r.iter().map(|v| v.truncate()).collect();
    if let Some(i) = light.iter().position(|v| !v.is_finite()) {
        bail!("the lightmap's texel {i} is not finite ({}): a bug; please report it", light[i]);
    }
    let valid = layout.texels.points.iter().map(Option::is_some).collect();
    let u = &layout.unwrapped;
    let mut atlas = Atlas::new((u.width, u.height, u.pages), light, valid);
    atlas.dilate();
    Ok(atlas)
}
