//! Structs shared with the shaders, defined once here and mirrored in `glsl/types.glsl` (std430 / push
//! constant layout). `tests/layout.rs` reads the member offsets and array strides out of the compiled SPIR-V
//! and compares them with these definitions, so the two cannot drift apart silently. No `vec3` members:
//! std430 aligns them to 16 bytes where Rust packs 12. A table of layouts, one file on purpose (over 500
//! lines): each struct beside the next, as `glsl/types.glsl` has them.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec4};

/// One vertex of the triangle soup (binding 0; attributes at the offsets below). Three per triangle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    /// The triangle's surface id (flat across its three vertices).
    pub surface: u32,
}

/// Material of a surface, indexed by surface id (entry 0 unused: "no surface").
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSurface {
    /// The surface's mean albedo (rgb): `Kd` times its texture's mean over the surface
    /// (`Mesh::surface_albedo`), what `Kd·ε` and the radiance cache's values carry; w unused.
    pub kd: Vec4,
    /// Emitted radiance `Ke` (rgb); w = its light group + 1 for an emitter (one-sided: front face only), else
    /// 0.
    pub ke: Vec4,
    /// `Kd` itself (rgb), which the G-buffer multiplies its texture by; w unused.
    pub kd_factor: Vec4,
    /// Its colour texture's index + 1 in the texture table (`GpuTexture`), 0 for none.
    pub kd_map: u32,
    /// Its emission texture's index + 1, 0 for none: what is seen of an emitter's front is `Ke` times it.
    pub ke_map: u32,
    /// Its cut-out's texture index + 1, 0 for none: a fragment whose texture alpha (bilinear, level 0) is
    /// under `alpha_threshold` is discarded (`material::Cutout`).
    pub alpha_map: u32,
    pub alpha_threshold: f32,
}

/// Where a texture's levels lie in the scene's texel buffer (`scene::texture` draws the layout).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTexture {
    /// First texel of level 0.
    pub offset: u32,
    /// Level 0's size; each further level halves it (rounded down, at least 1).
    pub width: u32,
    pub height: u32,
    pub levels: u32,
}

/// The sky map as the reduction reads it (`glsl/sky.glsl`): its level 0's size, its levels (0: no map) and
/// its turn about +y. Its texels lie in a buffer of their own, level 0 first (`scene::sky`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSky {
    pub width: u32,
    pub height: u32,
    pub levels: u32,
    pub _pad: u32,
    /// cos and sin of the map's turn about +y (`SkyMap::rotation_deg`); z, w unused.
    pub rotation: Vec4,
}

/// Push constants of the G-buffer pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GBufferPush {
    pub view_proj: Mat4,
}

/// One view of one sensor (paper §III-E): where it looks, what it keeps, and which layer it draws into.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSensorView {
    pub view_proj: Mat4,
    /// Planes `(m, d)` keeping `m·p + d ≥ 0`: the horizon `(n, −n·origin)` for hemicube side faces and zoom
    /// views, the frustum's four sides for a frustum sensor's zoom views; `(0,0,0,1)` clips nothing.
    pub clip: [Vec4; 4],
    /// Where the view looks from (w unused): the radiance cache decides which side of a split plane a
    /// fragment lies on a little towards it, so that a seam never reads the far side (`glsl/cache.glsl`).
    pub eye: Vec4,
    /// Layer of the sensor-map array this view writes (within its sensor until a strategy places it).
    pub layer: u32,
    /// [`VIEW_EMITTERS_ONLY`], [`VIEW_ZOOM`], or 0.
    pub flags: u32,
    pub _pad: [u32; 2],
}

/// A view that draws only the emitters (the unoccluded half of a zoom pair).
pub const VIEW_EMITTERS_ONLY: u32 = 1;
/// A zoom view (either of a pair): the reduction reads only which light group its texels see, so its
/// fragments skip the radiance cache (`glsl/sensor_shade.glsl`).
pub const VIEW_ZOOM: u32 = 2;

/// What the reduction needs of one sensor of a batch: where it sits and its domain.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSensor {
    /// xyz: the sensor's origin; w: the frustum's half-width `tan(fov/2)`, 0 for the whole hemisphere.
    pub origin: Vec4,
    /// The frame `(t, b, n)`; w unused.
    pub t: Vec4,
    pub b: Vec4,
    pub n: Vec4,
}

/// A sensor's zoom view of one light group: the square view its visibility is measured in.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuZoom {
    /// Unit axes of the view; `right.w` and `up.w`: tan of half its field of view along each, `forward.w` = 1
    /// where the group can be seen at all (else the group sends nothing and the view is empty).
    pub right: Vec4,
    pub up: Vec4,
    pub forward: Vec4,
}

/// An emitting triangle, group by group (see `light::groups`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuEmitter {
    /// Vertices, counter-clockwise seen from the emitting front; w unused.
    pub v0: Vec4,
    pub v1: Vec4,
    pub v2: Vec4,
    /// Emitted radiance; w unused.
    pub ke: Vec4,
}

/// A light group's chunks of emitters (a range of [`GpuEmitterChunk`]s).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuLightGroup {
    pub first_chunk: u32,
    pub chunks: u32,
    pub _pad: [u32; 2],
}

/// At most [`EMITTER_CHUNK`] emitters of one group: the emitter pass sums one chunk per invocation and
/// sensor, so that a group of thousands of triangles is spread over many invocations.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuEmitterChunk {
    pub first: u32,
    pub count: u32,
    pub group: u32,
    pub _pad: u32,
}

/// Emitters per chunk.
pub const EMITTER_CHUNK: u32 = 256;

/// Push constants of the emitter pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct EmitterPush {
    /// Sensors of the batch, chunks and light groups of the scene.
    pub sensors: u32,
    pub chunks: u32,
    pub groups: u32,
    pub _pad: u32,
}

/// Light groups a sensor measures at most (`light::groups::MAX_GROUPS`; fixed here for the shaders).
pub const MAX_GROUPS: usize = 8;

/// What the reduction reports of one sensor, for the host.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSensorResult {
    /// R; w = [`radiance_state::SENSED`].
    pub r: Vec4,
    /// Visibility of each light group (visible over unoccluded weighted coverage of its zoom view); −1 where
    /// the group sends this sensor nothing.
    pub visibility: [f32; MAX_GROUPS],
    /// R's part from the main layers (the indirect light, `Kd·ε`, the background: all but the exact
    /// estimator's `Σ E_g·V_g`); w: the share of the main layers' light that thin bright texels hold, a slit
    /// narrower than a texel (`glsl/reduce.comp`, `renderer::fine`).
    pub rest: Vec4,
}

/// Push constants of the sensor-map pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SensorPush {
    /// `Kd·ε` is what a non-emitting surface returns (paper eq. 2).
    pub epsilon: f32,
    /// First entry of the view buffer this draw reads (multiview: view of `gl_ViewIndex` 0; a draw from a
    /// per-view list: its view).
    pub first_view: u32,
    /// Subtracted from a view's layer: the first layer of the framebuffer (layered strategies).
    pub layer_base: u32,
    /// 1: the exact estimator (emitter fronts leave 0 and their group in the map; their light is computed
    /// exactly); 0: the paper's (emitter fronts leave `Ke`).
    pub exact: u32,
    /// The paper's estimator: emitter fronts leave `Ke / emission_scale`, a power of two that keeps them
    /// within the half-float maps' range (`passes::sensor_maps::emission_scale`).
    pub emission_scale: f32,
    /// 1: every surface returns the radiance cache's reflected light where the texel sees it (global
    /// illumination, docs/DESIGN.md §10) instead of `Kd·ε`; 0: `Kd·ε`.
    pub cache: u32,
}

/// The compute strategy's push constants (`passes::sensor_maps::compute`, `glsl/sensor_compute.comp`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SensorComputePush {
    /// What a texel that sees no geometry holds (the graphics strategies' clear colour).
    pub clear: Vec4,
    /// What the maps hold, as for the graphics strategies (`first_view` and `layer_base` unused).
    pub sensor: SensorPush,
    /// Texels per side of a map layer.
    pub rd: u32,
    /// Layers per sensor, and views per sensor in the view buffer.
    pub layers: u32,
    pub per_sensor: u32,
    /// Layers of the batch: one workgroup each.
    pub layer_count: u32,
    /// Full detail: the soup's triangles.
    pub triangles: u32,
    /// Culled (1): each view draws its own list of `max_per_view` slots, `counts[view]` of them used where
    /// `count_buffer` is 1, else all (the unused ones empty).
    pub max_per_view: u32,
    pub culled: u32,
    pub count_buffer: u32,
    pub _pad: [u32; 2],
}

/// The radiance cache's grid and table as the sensor maps' fragment shader reads them (`gi`): the head of the
/// table buffer, followed by its [`GpuCacheSlot`]s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCacheGrid {
    /// xyz: the grid's corner; w: 1 / cell size.
    pub origin: Vec4,
    /// Cells along x, y, z; w: slots − 1 (the table's size is a power of two).
    pub dims: [u32; 4],
    /// Entries of the values buffer before the per-surface fallbacks (`entries + 2·surface + side`).
    pub entries: u32,
    pub _pad: [u32; 3],
}

/// One slot of the cache's open-addressing table: a key (cell and surface) and where its fragments find
/// their pair of entries (`gi::SPLIT` | a split's index, or the pair's); `key[1] == 0` marks an empty slot
/// (surface 0 is no surface).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuCacheSlot {
    pub key: [u32; 2],
    pub entry: u32,
    pub _pad: u32,
}

/// A piece of the cache split by a plane (`gi::Split`): fragments with `plane · (p, 1) ≥ 0` go on to
/// `children[1]`, the others to `children[0]`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCacheSplit {
    pub plane: Vec4,
    pub children: [u32; 2],
    pub _pad: [u32; 2],
}

/// Push constants of the reduction: the map geometry (workgroup i reduces sensor i of the batch).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ReducePush {
    /// Sensor map side, texels.
    pub rd: u32,
    /// Layers per sensor: its main layers (1 frustum, 3 hemicube), then a zoom pair per light group.
    pub layers: u32,
    /// The main layers, summed with the precomputed weights.
    pub main_layers: u32,
    /// 0: sensor maps are layers of a 2D array. Otherwise tiles of one atlas with this many per row.
    pub atlas_columns: u32,
    /// Light groups measured (0: the paper's estimator), and the scene's emitter chunks (the stride of the
    /// emitter pass's irradiance, per sensor).
    pub groups: u32,
    pub chunks: u32,
    /// What texels of an emitter's front (alpha > 0) are multiplied by: the maps' `emission_scale`.
    pub emission_scale: f32,
    /// 1: the main layers hold the cache's entries (`CacheRead::Entries`), no light: they add nothing.
    pub main_entries: u32,
}

/// Push constants of the transport rows' pass (`passes::transport`, `glsl/transport.comp`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct TransportPush {
    /// Sensor map side, texels.
    pub rd: u32,
    /// Layers per sensor, and the main layers among them (the ones copied).
    pub layers: u32,
    pub main_layers: u32,
    /// 0: sensor maps are layers of a 2D array. Otherwise tiles of one atlas with this many per row.
    pub atlas_columns: u32,
}

/// Bits of a cache value's index per channel of a map drawn with `CacheRead::Entries` (`glsl/types.glsl`
/// `CACHE_ENTRY_BITS`: integers below 2¹¹ are exact in half floats).
pub const CACHE_ENTRY_BITS: u32 = 11;
/// Split nodes a cache lookup walks at most (`glsl/types.glsl` `CACHE_SPLIT_DEPTH`, `glsl/cache.glsl`): at
/// least the deepest split tree `gi::entries` builds, which it asserts. A walk cut short returned a split
/// node's index as an entry's: a fragment then read another piece's light.
pub const CACHE_SPLIT_DEPTH: u32 = 12;
/// A texel that sees no surface in the transport pass's texel list (`glsl/types.glsl` `TRANSPORT_NONE`).
pub const TRANSPORT_NONE: u32 = u32::MAX;

/// A quad of the adaptive refinement whose pixels are filled by bilinear interpolation (paper §III-G).
/// Corners are sensed pixels; the quad fills `[x0, own_x1] × [y0, own_y1]` (its share of shared edges).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuQuad {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
    pub own_x1: u32,
    pub own_y1: u32,
    pub _pad: [u32; 2],
}

/// Push constants of the interpolation that computes the emitters' light per pixel
/// (`glsl/interpolate_exact.comp`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ExactInterpolatePush {
    pub width: u32,
    /// Number of pixels to fill.
    pub count: u32,
    /// Light groups.
    pub groups: u32,
    /// A sensor's lift above its surface, world units (`SensorFrame::new`'s `bias`).
    pub bias: f32,
}

/// One sub-pixel sample of a supersampled pixel (docs/DESIGN.md §11, `glsl/resolve.comp`): what its camera
/// ray meets, and where its R comes from. Host twin: `supersample::SubSample`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSubSample {
    /// xyz: where the sample's camera ray meets a surface; w: 1 there, 0 where it leaves the scene.
    pub position: [f32; 4],
    /// Unit normal turned towards the camera.
    pub normal: [f32; 4],
    /// `Kd` at the sample; where it leaves the scene, the radiance it sees there (the sky along its ray).
    pub albedo: [f32; 4],
    /// Where w is 1, the sample's own R less its lights' light, taken instead of a donor's: the radiance
    /// cache's where no pixel around it shows its surface (`supersample::donor`, [`crate::gi`]).
    pub own: [f32; 4],
    /// The pixel whose final R the sample takes: the nearest on the same surface (`supersample::donor`).
    pub donor: u32,
    /// The share of its pixel's square the sample stands for (`supersample::coverage`).
    pub weight: f32,
    pub _pad: [u32; 2],
    /// With the exact light: each group's visibility at the sample, and at the donor (< 0: not measured).
    pub visibility: [f32; MAX_GROUPS],
    pub donor_visibility: [f32; MAX_GROUPS],
}

/// A supersampled pixel (`glsl/resolve.comp`): which, and the light its square emits, computed exactly on
/// the host (`supersample::emission`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSupersampledPixel {
    /// rgb: the mean emitted radiance over the square.
    pub emission: [f32; 4],
    pub pixel: u32,
    pub _pad: [u32; 3],
}

/// Push constants of the supersampling's resolve (`glsl/resolve.comp`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ResolvePush {
    pub width: u32,
    /// Supersampled pixels.
    pub count: u32,
    /// Sub-samples per supersampled pixel.
    pub samples: u32,
    /// Light groups.
    pub groups: u32,
    /// A sensor's lift above its surface, world units.
    pub bias: f32,
    /// 1: the light groups' light is computed at each sample (the exact interpolation's rule), 0: R is the
    /// donor's.
    pub exact: u32,
    pub _pad: [u32; 2],
}

/// Push constants of the passes that work on whole images (interpolation, filter, composition).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ImagePush {
    pub width: u32,
    pub height: u32,
    /// Filter radius in pixels (filter pass only).
    pub radius: u32,
    /// Number of items (quads for the interpolation pass).
    pub count: u32,
}

/// Push constants of the composition pass: the image size, whether R's indirect part was filtered apart, and
/// the background radiance that pixels without a surface show (docs/DESIGN.md §3 step 8).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ComposePush {
    /// Radiance of rays that leave the scene (rgb; w unused), where there is no sky map.
    pub background: [f32; 4],
    pub width: u32,
    pub height: u32,
    /// 1: R = R_f − I_f + I_i (the indirect part filtered apart); 0: R as it is.
    pub apart: u32,
    /// 1: a pixel without a surface shows its own sky (the sky map over its square, from the host); 0: the
    /// background.
    pub sky: u32,
}

/// Values of `w` in the radiance map: how a pixel's R was obtained.
pub mod radiance_state {
    pub const NONE: f32 = 0.0;
    pub const SENSED: f32 = 1.0;
    pub const INTERPOLATED: f32 = 2.0;
}

impl GpuSensorView {
    /// A view from `eye` of the whole scene clipped by `clip` (at most 4 planes).
    pub fn new(view_proj: Mat4, eye: glam::Vec3, clip: &[Vec4], layer: u32) -> Self {
        let mut planes = [Vec4::W; 4];
        planes[..clip.len()].copy_from_slice(clip);
        Self { view_proj, clip: planes, eye: eye.extend(1.0), layer, flags: 0, _pad: [0; 2] }
    }

    /// A view that draws nothing (its clip plane rejects every point): fills unused multiview slots and the
    /// zoom views of groups a sensor cannot see.
    pub fn empty(layer: u32) -> Self {
        let clip = [-Vec4::W, Vec4::W, Vec4::W, Vec4::W];
        Self { view_proj: Mat4::IDENTITY, clip, eye: Vec4::W, layer, flags: 0, _pad: [0; 2] }
    }

    pub fn emitters_only(mut self) -> Self {
        self.flags |= VIEW_EMITTERS_ONLY;
        self
    }

    /// Marked as a zoom view ([`VIEW_ZOOM`]).
    pub fn zoom(mut self) -> Self {
        self.flags |= VIEW_ZOOM;
        self
    }
}

/// `Vertex` as the raster pipelines read it from binding 0: (location, format, byte offset).
pub const VERTEX_ATTRIBUTES: [(u32, ash::vk::Format, u32); 2] = [
    (0, ash::vk::Format::R32G32B32_SFLOAT, std::mem::offset_of!(Vertex, position) as u32),
    (1, ash::vk::Format::R32_UINT, std::mem::offset_of!(Vertex, surface) as u32),
];
pub const VERTEX_STRIDE: u32 = size_of::<Vertex>() as u32;

const _: () = assert!(size_of::<Vertex>() == 16);

/// One cluster of the LOD hierarchy as the culling pass reads it (`crate::clusters::Cluster`, flattened).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCluster {
    /// Bounding sphere of its triangles: centre, radius.
    pub sphere: Vec4,
    /// The slab holding them: unit axis, half thickness about the sphere's centre (`clusters::reach`).
    pub slab: Vec4,
    /// The box of its triangles (xyz of min and max; w unused). Against a view's planes it is far tighter
    /// than the sphere for the long strips of a column: a fluted hall's sensors drew 2.7 times the
    /// triangles with the sphere alone.
    pub box_min: Vec4,
    pub box_max: Vec4,
    /// Its own error bound's box (xyz of min and max) and error (min's w; 0: full detail), and its
    /// parent's (error `f32::MAX`: terminal).
    pub own_min: Vec4,
    pub own_max: Vec4,
    pub parent_min: Vec4,
    pub parent_max: Vec4,
    pub first_index: u32,
    pub index_count: u32,
    /// [`CLUSTER_EMITTER`], [`CLUSTER_CLOSED`], or 0.
    pub flags: u32,
    pub _pad: u32,
    /// The box of its whole part and of the parts capping it (xyz of min and max; w unused): from outside
    /// it (and the near plane's distance) a [`CLUSTER_CLOSED`] part shows none of its back faces.
    pub part_min: Vec4,
    pub part_max: Vec4,
}

/// A cluster of an emitter (of a node: with an emitter below): the only ones an emitters-only view keeps.
pub const CLUSTER_EMITTER: u32 = 1;
/// A node whose children are clusters (`GpuCullNode::first` indexes the leaf items).
pub const NODE_LEAF: u32 = 2;
/// A cluster of a part that hides its back faces from outside `GpuCluster::part_min`..`part_max`: closed
/// and facing out, or capped by closed parts (`clusters::closed`).
pub const CLUSTER_CLOSED: u32 = 4;
/// Set in a kept command's entry (`passes::cull_triangles`) where the view's eye is outside the cluster's
/// closed part: the triangle pass drops its back faces.
pub const KEPT_BACK_HIDDEN: u32 = 1 << 31;

/// One node of the clusters' bounding tree as the culling pass reads it (`crate::clusters::TreeNode`
/// flattened; the same shape as [`GpuCluster`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCullNode {
    /// Holds every cluster's bounding sphere below: centre, radius.
    pub sphere: Vec4,
    /// A box holding every cluster's own box (min's w: the smallest own error below), and one holding
    /// every parent box (min's w: the largest parent error).
    pub own_min: Vec4,
    pub own_max: Vec4,
    pub parent_min: Vec4,
    pub parent_max: Vec4,
    /// Its first child (a node, or with [`NODE_LEAF`] a leaf item) and how many.
    pub first: u32,
    pub count: u32,
    /// [`CLUSTER_EMITTER`] (an emitter below) | [`NODE_LEAF`].
    pub flags: u32,
    pub _pad: u32,
}

/// `VkDrawIndexedIndirectCommand`, as the culling pass writes it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuDrawCommand {
    pub index_count: u32,
    pub instance_count: u32,
    pub first_index: u32,
    pub vertex_offset: i32,
    /// The view drawn (the sensor vertex shaders read `views[gl_InstanceIndex]`).
    pub first_instance: u32,
}

/// Push constants of one step of the culling pass's walk down the bounding tree.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CullPush {
    pub views: u32,
    /// Views per sensor: view `v` belongs to sensor `v / per_sensor`.
    pub per_sensor: u32,
    /// Command slots per view: view `v` writes commands `v · max_per_view ..`.
    pub max_per_view: u32,
    /// The sensor-map size: a view's accepted error is half its texel, `1 / (rd · scale)`.
    pub rd: u32,
    /// Distances below this count as this (the views' near plane).
    pub near: f32,
    /// The tree's root node: step 0 enters it for every view.
    pub root: u32,
    /// The depth this step takes its (node, view) pairs from; it queues their children at `step + 1`.
    pub step: u32,
    /// Where in the queue the pairs of depth `step` start and those of `step + 1`, and how many fit at each.
    pub in_base: u32,
    pub out_base: u32,
    pub out_capacity: u32,
    pub in_capacity: u32,
    /// The triangle pass (`passes::cull_triangles`): the indices in each view's region of the slot's pool
    /// (0: no triangle pass).
    pub region: u32,
    pub _pad: u32,
}
