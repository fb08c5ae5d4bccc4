//! A render's previews: the image so far on the host, after a round.

use glam::Vec4;

use crate::gbuffer::GBufferData;
use crate::light::groups::Lights;
use crate::sensors::refine::{self, Refinement, Visibility};

/// What the exact interpolation's CPU twin needs for a preview: per pixel, the sensed visibilities and R's
/// rest; the lights and the sensors' lift.
pub(super) struct PreviewLight<'a> {
    pub(super) visibility: &'a [Visibility],
    pub(super) rest: &'a [Vec4],
    pub(super) lights: &'a Lights,
    pub(super) bias: f32,
}

/// The image so far on the host, from the R sensed (`r`, where `refinement` sensed) interpolated over every
/// quad as the render's interpolation does (with `light`, the exact interpolation's CPU twin): unfiltered,
/// and only ever a preview (the render's own image comes from the GPU passes).
pub(super) fn preview(
    g: &GBufferData,
    r: &[Vec4],
    refinement: &Refinement,
    (background, sky): (glam::Vec3, Option<&[glam::Vec3]>),
    light: Option<PreviewLight<'_>>,
) -> Vec<Vec4> {
    use crate::gpu_types::radiance_state::SENSED;
    let sensed = |v: &[Vec4]| -> Vec<Vec4> {
        (v.iter().enumerate())
            .map(|(i, v)| if refinement.is_sensed(i) { v.truncate().extend(SENSED) } else { Vec4::ZERO })
            .collect()
    };
    let mut radiance = sensed(r);
    let quads = refinement.coverage();
    match light {
        Some(l) => {
            let corners = refine::corner_visibility(l.visibility, g.size.width, &quads);
            let rest = sensed(l.rest);
            refine::interpolate_exact_cpu((&mut radiance, &rest), &corners, (g, l.lights, l.bias), &quads);
        }
        None => refine::interpolate_cpu(&mut radiance, g.size.width, &quads),
    }
    (g.surface.iter().zip(&g.emission).zip(&g.albedo).zip(&radiance).enumerate())
        .map(|(i, (((&id, le), kd), r))| match id {
            crate::scene::NO_SURFACE => sky.map_or(background, |s| s[i]).extend(0.0),
            _ => (le.truncate() + kd.truncate() * r.truncate()).extend(1.0),
        })
        .collect()
}
