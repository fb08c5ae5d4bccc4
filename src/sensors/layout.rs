//! How a sensor's faces map onto layers of the sensor-map array (`rd × rd` texels per layer).
//!
//! A frustum sensor is one layer: a square perspective view along `n`.
//!
//! A hemicube is three layers. The side faces are 90° views along ±t and ±b of which only the half above
//! the horizon counts, so two of them share a layer, each clipped at the horizon (`gl_ClipDistance`):
//!
//! ```text
//!   layer 0            layer 1               layer 2
//!  +---------+       +---------+ row 0      +---------+
//!  |         |       |  +t, up |            |  +b, up |      n (up) points to the top edge
//!  |  front  |       |---------| ← horizon  |---------|
//!  | along n |       |  −t, up |            |  −b, up |      n points to the bottom edge
//!  +---------+       +---------+ row rd−1   +---------+
//! ```
//!
//! The lower half of layer 1 is the −t face seen with `up = −n`, so its horizon also lies on the middle line
//! and its zenith on the bottom edge. Every texel then covers the same solid angle as in a textbook
//! hemicube of `rd × rd` front texels, and the sensor costs 3 layers instead of 5.
//!
//! With the exact estimator a sensor also has a pair of zoom layers per light group (`sensors::zoom`),
//! after its main layers: the group's zoom view drawn with the whole scene, then with the emitters alone.
//!
//! ```text
//!   | main 0 … main L−1 | group 0, scene | group 0, emitters | group 1, scene | group 1, emitters | … |
//! ```

use super::SensorKind;

/// The layers one sensor occupies: its main layers, then a zoom pair per light group measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorLayout {
    pub kind: SensorKind,
    /// Light groups whose visibility the sensor measures (0: the paper's estimator).
    pub groups: u32,
}

impl SensorLayout {
    pub fn main_layers(&self) -> u32 {
        self.kind.layers()
    }

    pub fn layers(&self) -> u32 {
        self.main_layers() + 2 * self.groups
    }

    /// Views per sensor: the main ones and two per group.
    pub fn views(&self) -> u32 {
        self.kind.views() + 2 * self.groups
    }

    /// Layer of group `g`'s zoom view drawn with the whole scene (`emitters_only`: with the emitters alone).
    pub fn zoom_layer(&self, g: u32, emitters_only: bool) -> u32 {
        self.main_layers() + 2 * g + emitters_only as u32
    }

    /// The layer of each of a sensor's views, in their order: the main views, then each group's pair.
    pub fn view_layers(&self) -> Vec<u32> {
        let zooms = (0..self.groups).flat_map(|g| [self.zoom_layer(g, false), self.zoom_layer(g, true)]);
        views(self.kind).iter().map(|v| v.layer).chain(zooms).collect()
    }
}

/// What one layer holds; decides its weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LayerKind {
    /// A perspective view along `n` covering `[-s, s]²` of the plane `z = 1` (`s = tan(fov/2)`).
    Front { s: f64 },
    /// Two 90° side faces, upper half of the rows one face, lower half the other; horizon in the middle.
    SidePair,
}

/// Orientation of one view relative to the sensor frame `(t, b, n)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Axis {
    T,
    NegT,
    B,
    NegB,
    N,
    NegN,
}

/// One view (draw) of a sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewLayout {
    /// Layer within the sensor's layers.
    pub layer: u32,
    pub forward: Axis,
    /// The camera's up axis (image rows run from +up at row 0 to −up).
    pub up: Axis,
    /// Field of view of the square view, degrees.
    pub fov_deg: f32,
    /// Clip at the horizon: keep only what lies above the sensor's tangent plane.
    pub clip_horizon: bool,
}

pub fn layers(kind: SensorKind) -> Vec<LayerKind> {
    match kind {
        SensorKind::Frustum { fov_deg } => vec![LayerKind::Front { s: (fov_deg as f64 * 0.5).to_radians().tan() }],
        SensorKind::Hemicube => vec![LayerKind::Front { s: 1.0 }, LayerKind::SidePair, LayerKind::SidePair],
    }
}

pub fn views(kind: SensorKind) -> Vec<ViewLayout> {
    let front = |fov_deg| ViewLayout { layer: 0, forward: Axis::N, up: Axis::B, fov_deg, clip_horizon: false };
    let side = |layer, forward, up| ViewLayout { layer, forward, up, fov_deg: 90.0, clip_horizon: true };
    match kind {
        SensorKind::Frustum { fov_deg } => vec![front(fov_deg)],
        SensorKind::Hemicube => vec![
            front(90.0),
            side(1, Axis::T, Axis::N),
            side(1, Axis::NegT, Axis::NegN),
            side(2, Axis::B, Axis::N),
            side(2, Axis::NegB, Axis::NegN),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_match_the_diagram() {
        assert_eq!(SensorKind::Hemicube.layers(), 3);
        assert_eq!(SensorKind::Hemicube.views(), 5);
        assert_eq!(SensorKind::Frustum { fov_deg: 135.0 }.layers(), 1);
        let layers: Vec<u32> = views(SensorKind::Hemicube).iter().map(|v| v.layer).collect();
        assert_eq!(layers, [0, 1, 1, 2, 2]);
    }

    #[test]
    fn frustum_half_width_is_tan_of_half_fov() {
        let LayerKind::Front { s } = layers(SensorKind::Frustum { fov_deg: 135.0 })[0] else { panic!() };
        assert!((s - (67.5f64).to_radians().tan()).abs() < 1e-12);
    }
}
