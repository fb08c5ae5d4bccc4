//! How a renderer estimates R for its scene, decided once when it is built and read by every phase: whether
//! its sensors measure the lights' visibility, whether the lights' light is computed in closed form per
//! pixel and per cache entry, and how far sensors sit off their surfaces.

use super::config::RendererConfig;
use crate::gpu_types::EMITTER_CHUNK;
use crate::light::groups::Lights;
use crate::sensors::{SensorKind, frame};

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Estimate {
    /// Light groups whose visibility each sensor measures in zoom views (the exact estimator with lights);
    /// 0: none, R is what the maps see.
    pub(super) groups: u32,
    /// At most one emitter chunk of emissive triangles: a loop over them costs less per pixel (or per cache
    /// entry) than a sensor's emitter pass; with thousands it would cost more (docs/ACCURACY.md).
    pub(super) few_emitters: bool,
    /// The interpolation computes each light group's unoccluded light per pixel and interpolates only the
    /// visibilities and the rest of R (`interpolate_exact.comp`), so the refinement judges those: with
    /// measured groups, few emitters, and the hemicube (a domain the same whatever a sensor's turn).
    pub(super) exact_interpolation: bool,
    /// The radiance cache's direct light by shadow rays and the closed form (`gi::DirectByRays`), with
    /// measured groups and few emitters; else by the render's sensors.
    pub(super) direct_by_rays: bool,
    /// The sensors' lift off their surface and their views' near plane, in scene units
    /// ([`frame::offsets`]).
    pub(super) offsets: (f32, f32),
}

impl Estimate {
    /// The decision for a renderer of `config` over a scene with `lights`, `scale` its diagonal.
    pub(super) fn new(config: &RendererConfig, lights: &Lights, scale: f32) -> Self {
        let groups = config.layout(lights).groups;
        let few_emitters = lights.emitters.len() <= EMITTER_CHUNK as usize;
        Self {
            groups,
            few_emitters,
            exact_interpolation: groups > 0 && few_emitters && config.sensor == SensorKind::Hemicube,
            direct_by_rays: groups > 0 && few_emitters,
            offsets: frame::offsets(scale),
        }
    }
}
