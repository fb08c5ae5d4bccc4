//! A batch of sensors as the GPU draws and reduces them: every sensor's views (its main views, then a zoom
//! pair per light group, layers as `SensorLayout` places them), and what the reduction needs to know of each
//! sensor (its frame and domain) and of each of its zoom views (their axes and width). Strategies only place
//! the views into layers or tiles.

use glam::Vec4;

use super::SensorKind;
use super::frame::SensorFrame;
use super::layout::{SensorLayout, views};
use super::zoom::Zoom;
use crate::gpu_types::{GpuSensor, GpuSensorView, GpuZoom};
use crate::scene::Aabb;

#[derive(Clone, Debug, Default)]
pub struct BatchViews {
    /// Views per sensor (`SensorLayout::views`).
    pub per_sensor: usize,
    /// Sensor-major; each view's `layer` is its layer within its sensor.
    pub views: Vec<GpuSensorView>,
    pub sensors: Vec<GpuSensor>,
    /// `[sensor][group]`.
    pub zooms: Vec<GpuZoom>,
}

impl BatchViews {
    /// The views of the sensors at `frames`, with near plane `near`; `groups` holds each light group's
    /// bounding box (`layout.groups` of them); `rd` the map size (a zoom view is widened by a texel).
    pub fn new(frames: &[SensorFrame], layout: &SensorLayout, near: f32, groups: &[Aabb], rd: u32) -> Self {
        let main = views(layout.kind);
        let per_sensor = layout.views() as usize;
        let mut batch = Self {
            per_sensor,
            views: Vec::with_capacity(frames.len() * per_sensor),
            sensors: Vec::with_capacity(frames.len()),
            zooms: Vec::with_capacity(frames.len() * layout.groups as usize),
        };
        let half_width = match layout.kind {
            SensorKind::Frustum { fov_deg } => (fov_deg.to_radians() * 0.5).tan(),
            SensorKind::Hemicube => 0.0,
        };
        for frame in frames {
            for v in &main {
                let clip: &[Vec4] = if v.clip_horizon { &[frame.horizon()] } else { &[] };
                batch.views.push(GpuSensorView::new(frame.view_proj(v, near), frame.origin, clip, v.layer));
            }
            // A zoom view is clipped to the sensor's domain, as the exact irradiance it measures the
            // visibility of.
            let domain: Vec<Vec4> = if half_width == 0.0 {
                vec![frame.horizon()]
            } else {
                [frame.n * half_width - frame.t, frame.n * half_width + frame.t]
                    .into_iter()
                    .chain([frame.n * half_width - frame.b, frame.n * half_width + frame.b])
                    .map(|m| m.extend(-m.dot(frame.origin)))
                    .collect()
            };
            for (g, bounds) in groups.iter().enumerate().take(layout.groups as usize) {
                let (scene, alone) = (layout.zoom_layer(g as u32, false), layout.zoom_layer(g as u32, true));
                match Zoom::towards(frame.origin, frame.n, bounds, frame.b, 2.0 / rd as f32) {
                    Some(zoom) => {
                        // Nothing farther along the view than the group's farthest corner can hide it: a
                        // plane there (where a slot is free) leaves it out, the ceiling behind a lamp and all.
                        let mut planes = domain.clone();
                        if planes.len() < 4 {
                            planes.push(zoom.far_plane(frame.origin, bounds, near));
                        }
                        let view =
                            GpuSensorView::new(zoom.view_proj(frame.origin, near), frame.origin, &planes, scene).zoom();
                        batch.views.push(view);
                        batch.views.push(GpuSensorView { layer: alone, ..view }.emitters_only());
                        batch.zooms.push(GpuZoom {
                            right: zoom.right.extend(zoom.tan_half.x),
                            up: zoom.up.extend(zoom.tan_half.y),
                            forward: zoom.forward.extend(1.0),
                        });
                    }
                    None => {
                        batch.views.push(GpuSensorView::empty(scene));
                        batch.views.push(GpuSensorView::empty(alone));
                        batch.zooms.push(GpuZoom::default());
                    }
                }
            }
            batch.sensors.push(GpuSensor {
                origin: frame.origin.extend(half_width),
                t: frame.t.extend(0.0),
                b: frame.b.extend(0.0),
                n: frame.n.extend(0.0),
            });
        }
        batch
    }

    pub fn len(&self) -> usize {
        self.sensors.len()
    }

    pub fn is_empty(&self) -> bool {
        self.sensors.is_empty()
    }

    /// The views of sensor `i`.
    pub fn of(&self, i: usize) -> &[GpuSensorView] {
        &self.views[i * self.per_sensor..(i + 1) * self.per_sensor]
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::gpu_types::{VIEW_EMITTERS_ONLY, VIEW_ZOOM};

    #[test]
    fn each_sensor_has_its_main_views_then_a_zoom_pair_per_group() {
        let frames =
            [SensorFrame::new(Vec3::ZERO, Vec3::Y, 0.01), SensorFrame::new(Vec3::new(1.0, 0.0, 0.0), Vec3::Y, 0.01)];
        let lamps = [
            Aabb { min: Vec3::new(-0.1, 2.0, -0.1), max: Vec3::new(0.1, 2.0, 0.1) },
            Aabb { min: Vec3::new(-1.0, -3.0, -1.0), max: Vec3::new(1.0, -2.0, 1.0) }, // below every horizon
        ];
        let layout = SensorLayout { kind: SensorKind::Hemicube, groups: 2 };
        let batch = BatchViews::new(&frames, &layout, 1e-3, &lamps, 64);
        assert_eq!((batch.len(), batch.per_sensor, batch.zooms.len()), (2, 9, 4));
        let layers: Vec<u32> = batch.of(1).iter().map(|v| v.layer).collect();
        assert_eq!(layers, [0, 1, 1, 2, 2, 3, 4, 5, 6], "main layers, then (scene, emitters) per group");
        assert_eq!(layers, layout.view_layers(), "the layout says the same");
        let flags: Vec<u32> = batch.of(0).iter().map(|v| v.flags).collect();
        assert_eq!(flags[..5], [0; 5], "main views");
        assert_eq!(flags[5..7], [VIEW_ZOOM, VIEW_ZOOM | VIEW_EMITTERS_ONLY], "a pair, the second the emitters alone");
        // A zoom view keeps its group and what lies before it, not what lies beyond (its second clip plane).
        let (far, frame) = (batch.of(0)[5].clip[1], &frames[0]);
        let keeps = |p: Vec3| far.truncate().dot(p) + far.w >= 0.0;
        let beyond = frame.origin + (lamps[0].center() - frame.origin) * 1.5;
        assert!(keeps(lamps[0].min) && keeps(lamps[0].max) && keeps(frame.origin) && !keeps(beyond));
        assert!(batch.zooms[0].forward.w == 1.0 && batch.zooms[1].forward.w == 0.0, "a group below is not seen");
        assert_eq!(batch.of(0)[7].clip[0], -Vec4::W, "its views draw nothing");
        // A frustum sensor's zoom views are clipped to its four sides; its domain's half-width is recorded.
        let layout = SensorLayout { kind: SensorKind::Frustum { fov_deg: 90.0 }, groups: 1 };
        let batch = BatchViews::new(&frames[..1], &layout, 1e-3, &lamps[..1], 64);
        assert!(batch.of(0)[1].clip.iter().all(|c| *c != Vec4::W));
        assert!((batch.sensors[0].origin.w - 1.0).abs() < 1e-6);
    }
}
