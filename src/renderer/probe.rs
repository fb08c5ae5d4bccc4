//! The probe the strategy module measures on: sensors at fixed pixels of the built-in lightbox, sensed by a
//! renderer built with the strategy under test. Renderers are kept per (strategy, size, batch), so a
//! strategy's pipelines compile once however often it is probed.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use anyhow::Result;
use glam::{Vec3, Vec4};

use super::{Renderer, RendererConfig};
use crate::params::{EstimatorKind, FrameParams, Indirect};
use crate::passes::sensor_maps::{self, StrategyDesc};
use crate::scene::{ImageSize, NO_SURFACE, Scene, SurfaceId, builtin};
use crate::sensors::layout::SensorLayout;
use crate::strategy::{self, Prober, StrategyKind, StrategyRequest};
use crate::vk::Device;

/// The probe's view: the built-in lightbox at this size.
const PROBE_SIZE: ImageSize = ImageSize { width: 32, height: 32 };

/// ε and background of the probe: non-zero, so that every part of `Ck` is exercised.
const PROBE_FRAME: FrameParams = FrameParams::every_pixel(Indirect::Epsilon(0.2), Vec3::splat(0.05));

pub(crate) struct ProbeRenderer<'a> {
    device: &'a Arc<Device>,
    scene: Scene,
    /// The renderer being built: its sensors, estimator and batches in flight.
    config: RendererConfig,
    /// Bytes per batch when the probe does not ask for a batch size.
    budget: u64,
    /// Light groups of the scene the strategy is chosen for: a strategy must run with its sensors too.
    groups: u32,
    renderers: HashMap<(StrategyKind, u32, Option<u32>), Renderer>,
}

impl<'a> ProbeRenderer<'a> {
    /// The probe for choosing a strategy for a scene whose sensors measure `groups` light groups (0 for
    /// the self-check alone).
    pub fn new(device: &'a Arc<Device>, config: &RendererConfig, budget: u64, groups: u32) -> Self {
        let scene = builtin::lightbox(PROBE_SIZE);
        Self { device, scene, config: *config, budget, groups, renderers: HashMap::new() }
    }
}

impl Prober for ProbeRenderer<'_> {
    fn device_name(&self) -> String {
        self.device.adapter.to_string()
    }

    fn device_key(&self) -> String {
        strategy::device_key(&self.device.adapter)
    }

    fn unsupported(&self, kind: StrategyKind, rd: u32) -> Option<String> {
        // The probe's lightbox has one light, the scene `groups`: the larger layout the strategy meets
        // (multiview's view count may hold the probe's sensors and not the scene's).
        let groups = match self.config.estimator {
            EstimatorKind::Exact => self.groups.max(1),
            EstimatorKind::Paper => 0,
        };
        let layout = SensorLayout { kind: self.config.sensor, groups };
        let desc = StrategyDesc {
            layout,
            fronts: super::build::fronts(self.config.estimator),
            rd,
            budget: self.budget,
            cull_triangles: self.config.cull_triangles(),
        };
        sensor_maps::unsupported(kind, self.device, &desc)
    }

    fn probe(
        &mut self,
        kind: StrategyKind,
        rd: u32,
        sensors: usize,
        batch: Option<u32>,
    ) -> Result<(Vec<Vec4>, Duration)> {
        let renderer = match self.renderers.entry((kind, rd, batch)) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => {
                let config = RendererConfig {
                    sensor_size: rd,
                    memory_budget: Some(self.budget),
                    max_batch: batch,
                    strategy: StrategyRequest::Fixed(kind),
                    // The probe checks how strategies rasterize, on a scene too small for clusters anyway.
                    detail: super::Detail::Full,
                    ..self.config
                };
                e.insert(Renderer::new(
                    self.device,
                    &self.scene,
                    config,
                    strategy::Choice { strategy: kind, reason: "probe".into() },
                )?)
            }
        };
        let g = renderer.gbuffer(PROBE_SIZE)?;
        let pixels = probe_pixels(&g.surface, sensors);
        renderer.sense_at(PROBE_SIZE, &pixels, &PROBE_FRAME)
    }
}

/// `count` surface pixels (fewer if there are fewer), spread evenly over the image in row order.
pub fn probe_pixels(surface: &[SurfaceId], count: usize) -> Vec<u32> {
    let surfaces: Vec<u32> = (0..surface.len() as u32).filter(|&i| surface[i as usize] != NO_SURFACE).collect();
    let n = count.min(surfaces.len());
    (0..n).map(|k| surfaces[k * surfaces.len() / n]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probe_pixels_are_distinct_surface_pixels_spread_over_the_image() {
        let surface: Vec<SurfaceId> = (0..100).map(|i| if i % 3 == 0 { NO_SURFACE } else { 1 }).collect();
        let pixels = probe_pixels(&surface, 10);
        assert_eq!(pixels.len(), 10);
        assert!(pixels.iter().all(|&p| surface[p as usize] != NO_SURFACE));
        assert!(pixels.windows(2).all(|w| w[0] < w[1]), "distinct, in order: {pixels:?}");
        assert!(*pixels.last().unwrap() > 80, "spread to the end: {pixels:?}");
        assert_eq!(probe_pixels(&surface, 1000).len(), 66, "no more than the surface pixels");
    }
}
