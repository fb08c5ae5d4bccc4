//! What a renderer is built for: the sensors, the estimator, the batches' memory, the level of detail and
//! the radiance cache. These fix its pipelines and maps; the rest is chosen per render (`FrameParams`).

use crate::light::groups::Lights;
use crate::params::{EstimatorKind, RenderParams};
use crate::passes::sensor_maps::TEXEL_BYTES;
use crate::sensors::SensorKind;
use crate::sensors::layout::SensorLayout;
use crate::strategy::{StrategyKind, StrategyRequest};
use crate::vk::Device;

/// Batches in flight by default: one rendering while the host prepares the next.
pub const DEFAULT_IN_FLIGHT: u32 = 2;

/// Where [`Detail::Auto`] cannot measure (the camera sees nothing of the mesh), meshes of at least this many
/// triangles are drawn from their clusters: full detail costs per sensor in proportion to the triangles
/// (on lavapipe 36× the Cornell box at 10 000, the clusters 1.6×: docs/BENCHMARKS.md "Large meshes").
/// Otherwise every mesh from [`detail::DETAIL_PROBE_MIN_TRIANGLES`] on is drawn whichever way measures
/// faster on the device ([`detail`]); smaller ones at full detail.
pub const CLUSTER_MIN_TRIANGLES: usize = 5_000;

/// How finely the sensor maps draw the scene (docs/DESIGN.md §9). The camera's G-buffer and the emitters
/// are always full detail.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Detail {
    /// Clusters where they measure faster ([`detail`]: from [`detail::DETAIL_PROBE_MIN_TRIANGLES`]
    /// triangles on, where the device can draw them; unmeasured, from [`CLUSTER_MIN_TRIANGLES`]).
    #[default]
    Auto,
    /// Every view draws every triangle.
    Full,
    /// Clusters whatever the mesh's size, where the device can draw them.
    Clusters,
    /// As `Clusters`, each cluster drawn whole: without the triangle pass (`passes::cull_triangles`), as the
    /// maps were drawn before it; for benchmarks and the tests that hold the two alike.
    WholeClusters,
}

impl Detail {
    pub(super) fn wants_clusters(self, triangles: usize) -> bool {
        match self {
            Detail::Auto => triangles >= CLUSTER_MIN_TRIANGLES,
            Detail::Full => false,
            Detail::Clusters | Detail::WholeClusters => triangles > 0,
        }
    }
}

/// What a renderer is built for. These fix its pipelines and sensor maps; everything else is chosen per
/// render ([`FrameParams`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RendererConfig {
    /// How R is estimated: the exact estimator adds a zoom pair of layers per light group.
    pub estimator: EstimatorKind,
    pub sensor: SensorKind,
    /// rd: sensor map side in texels (see `params::RenderParams::sensor_size`).
    pub sensor_size: u32,
    /// Bytes for one batch's sensor maps and depth; `None`: [`default_memory_budget`].
    pub memory_budget: Option<u64>,
    /// At most this many sensors per batch, whatever the budget (the self-check's partial batches, tests).
    pub max_batch: Option<u32>,
    /// Batches in flight, ≥ 1 (each has its own maps: memory grows with it).
    pub in_flight: u32,
    pub strategy: StrategyRequest,
    pub detail: Detail,
    /// The radiance cache, for renders with global illumination (`None`: the renderer has none and renders
    /// the paper's ε only).
    pub cache: Option<CacheConfig>,
}

/// The radiance cache of a renderer for global illumination (docs/DESIGN.md §10).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct CacheConfig {
    /// Cells along the scene's longest side (`params::RenderParams::cache_resolution`).
    pub resolution: u32,
    /// rd of the sensors that measure what the entries see of the sky, and of the bounces after the first
    /// where the transport's rows would exceed `transport_budget` (the first measures the direct light and
    /// the rows at the renderer's own rd).
    pub sensor_size: u32,
    /// Host bytes the transport's rows may take (`gi::transport`), beyond which the bounces after the
    /// first are sensed again.
    pub transport_budget: u64,
}

impl CacheConfig {
    /// A cache of `resolution` cells along the scene's longest side, sensors of `sensor_size` where its
    /// bounces are sensed, and the default budget for the transport's rows.
    pub fn new(resolution: u32, sensor_size: u32) -> Self {
        Self { resolution, sensor_size, transport_budget: crate::gi::transport::DEFAULT_BUDGET }
    }

    /// The cache `params` ask for: with global illumination, of their resolution and sensor size.
    pub fn for_params(params: &RenderParams) -> Option<Self> {
        let (resolution, sensor_size) = (params.values.cache_resolution, params.values.cache_sensor_size);
        params.estimator.indirect.bounces().map(|_| Self::new(resolution, sensor_size))
    }
}

impl RendererConfig {
    /// Whether maps drawn from clusters run the triangle pass (all but [`Detail::WholeClusters`]).
    pub fn cull_triangles(&self) -> bool {
        self.detail != Detail::WholeClusters
    }

    /// A renderer for sensors of `sensor` kind and size `sensor_size` read by `estimator`: the `auto`
    /// strategy and level of detail, the default budget and batches in flight, no radiance cache.
    pub fn new(estimator: EstimatorKind, sensor: SensorKind, sensor_size: u32) -> Self {
        Self {
            estimator,
            sensor,
            sensor_size,
            memory_budget: None,
            max_batch: None,
            in_flight: DEFAULT_IN_FLIGHT,
            strategy: StrategyRequest::Auto,
            detail: Detail::Auto,
            cache: None,
        }
    }

    /// [`RendererConfig::new`] with strategy `kind` and every triangle drawn: what the strategies' checks
    /// and their support are judged on.
    pub fn fixed(estimator: EstimatorKind, sensor: SensorKind, sensor_size: u32, kind: StrategyKind) -> Self {
        Self {
            strategy: StrategyRequest::Fixed(kind),
            detail: Detail::Full,
            ..Self::new(estimator, sensor, sensor_size)
        }
    }

    /// The layers one sensor occupies with the scene's `lights`: the main layers, and with the exact
    /// estimator a zoom pair per light group.
    pub fn layout(&self, lights: &Lights) -> SensorLayout {
        let groups = match self.estimator {
            EstimatorKind::Exact => lights.groups.len() as u32,
            EstimatorKind::Paper => 0,
        };
        SensorLayout { kind: self.sensor, groups }
    }

    /// Bytes for one batch's maps and depth, sensors of `layout`: at most `max_batch` sensors' worth, else
    /// the memory budget.
    pub(super) fn batch_budget(&self, device: &Device, layout: &SensorLayout) -> u64 {
        let per_sensor = layout.layers() as u64 * (self.sensor_size as u64).pow(2) * TEXEL_BYTES;
        let budget = self.memory_budget.unwrap_or_else(|| default_memory_budget(device, self.in_flight));
        self.max_batch.map_or(budget, |n| budget.min(n as u64 * per_sensor))
    }
}

/// Budget for one batch's sensor maps when none is given: together, the batches in flight use an eighth
/// of the device's largest local heap.
pub fn default_memory_budget(device: &Device, in_flight: u32) -> u64 {
    device.adapter.device_local_bytes / 8 / in_flight.max(1) as u64
}
