// Structs shared with Rust: the one mirror of src/gpu_types.rs (std430 and push-constant layout).
// tests/layout.rs compares member offsets and array strides in the compiled SPIR-V with the Rust structs.
#ifndef TYPES_GLSL
#define TYPES_GLSL

// Indexed by surface id; entry 0 is "no surface".
struct GpuSurface {
    vec4 kd;         // mean albedo (rgb): Kd times its texture's mean over the surface
    vec4 ke;         // emitted radiance Ke (rgb); w = light group + 1 for an emitter (front face only), else 0
    vec4 kd_factor;  // Kd itself (rgb): the G-buffer multiplies its texture by it
    uint kd_map;     // colour texture index + 1 (GpuTexture), 0 for none
    uint ke_map;     // emission texture index + 1, 0 for none: an emitter's front emits Ke times it
    uint alpha_map;  // cut-out texture index + 1, 0 for none: discarded where its alpha < alpha_threshold
    float alpha_threshold;
};

// Where a texture's levels lie in the scene's texel buffer (src/scene/texture.rs draws the layout).
struct GpuTexture {
    uint offset;  // first texel of level 0
    uint width;   // level 0; each further level halves (rounded down, at least 1)
    uint height;
    uint levels;
};

struct GBufferPush {
    mat4 view_proj;
};

struct GpuSensorView {
    mat4 view_proj;
    vec4 clip[4];  // keep dot(clip[k], vec4(p, 1)) >= 0
    vec4 eye;      // where it looks from (w unused)
    uint layer;    // layer of the sensor-map array
    uint flags;    // VIEW_EMITTERS_ONLY
    uint _pad[2];
};

const uint VIEW_EMITTERS_ONLY = 1u;
const uint VIEW_ZOOM = 2u;  // a zoom view: only its texels' light groups are read

struct GpuSensor {
    vec4 origin;  // w: frustum half-width tan(fov/2), 0 for the hemisphere
    vec4 t;
    vec4 b;
    vec4 n;
};

struct GpuZoom {
    vec4 right;    // w: tan of half the field of view along right
    vec4 up;       // w: along up
    vec4 forward;  // w: 1 where the group can be seen
};

struct GpuEmitter {
    vec4 v0;  // counter-clockwise seen from the emitting front
    vec4 v1;
    vec4 v2;
    vec4 ke;
};

struct GpuLightGroup {
    uint first_chunk;
    uint chunks;
    uint _pad[2];
};

struct GpuEmitterChunk {
    uint first;
    uint count;
    uint group;
    uint _pad;
};

struct EmitterPush {
    uint sensors;  // of the batch
    uint chunks;   // of the scene
    uint groups;
    uint _pad;
};

const uint MAX_GROUPS = 8u;

struct GpuSensorResult {
    vec4 r;
    float visibility[MAX_GROUPS];  // -1 where the group sends nothing
    vec4 rest;                     // R's part from the main layers (all but the groups' exact light);
                                   // w: the share of it thin bright texels hold (reduce.comp)
};

struct SensorPush {
    float epsilon;       // non-emitters return Kd * epsilon (paper eq. 2)
    uint first_view;     // first entry of the view buffer for this draw (multiview; a per-view list's view)
    uint layer_base;     // subtracted from a view's layer (layered strategies)
    uint exact;          // 1: emitter fronts leave 0 and their group; 0: they leave Ke (the paper's)
    float emission_scale;  // the paper's: emitter fronts leave Ke / emission_scale (a power of two, f16 range)
    uint cache;          // CACHE_*: what surfaces return besides Kd * epsilon
};

// SensorPush.cache (src/passes/sensor_maps CacheRead): nothing; the radiance cache's reflected light where
// the texel sees it (cache.glsl); or which of the cache's values it reads (CACHE_ENTRY_BITS a channel,
// alpha CACHE_ENTRY_MARK on a surface, an emitter front's group + 1 kept), for the transport's rows.
const uint CACHE_OFF = 0u;
const uint CACHE_VALUES = 1u;
const uint CACHE_ENTRIES = 2u;
const uint CACHE_ENTRY_BITS = 11u;
const float CACHE_ENTRY_MARK = 0.5;

// The compute strategy's push (src/passes/sensor_maps/compute.rs, sensor_compute.comp).
struct SensorComputePush {
    vec4 clear;          // what a texel that sees no geometry holds
    SensorPush sensor;   // what the maps hold (first_view, layer_base unused)
    uint rd;             // texels per side of a map layer
    uint layers;         // layers per sensor
    uint per_sensor;     // views per sensor in the view buffer
    uint layer_count;    // layers of this batch: one workgroup each
    uint triangles;      // the soup's triangles (full detail)
    uint max_per_view;   // culled: draw-list slots per view
    uint culled;         // 1: each view draws its culled list; 0: the whole soup
    uint count_buffer;   // culled: each view's list length is counts[view]; 0: every slot (unused ones empty)
    uint _pad[2];
};

// The radiance cache's grid (src/gi): the head of the table buffer, its slots after it.
struct GpuCacheGrid {
    vec4 origin;   // w: 1 / cell size
    uvec4 dims;    // cells along x, y, z; w: slots - 1
    uint entries;  // values[entries + 2 * surface + side]: a surface side's fallback
    uint _pad[3];
};

// key = (packed cell, surface); key.y == 0: an empty slot. entry: CACHE_SPLIT | split, or a pair of entries.
struct GpuCacheSlot {
    uvec2 key;
    uint entry;
    uint _pad;
};

// Fragments with dot(plane, vec4(p, 1)) >= 0 go on to children[1], the others to children[0].
struct GpuCacheSplit {
    vec4 plane;
    uvec2 children;
    uint _pad[2];
};

const uint CACHE_SPLIT = 0x80000000u;
// Split nodes a lookup walks at most (src/gpu_types.rs CACHE_SPLIT_DEPTH: at least the deepest tree's).
const uint CACHE_SPLIT_DEPTH = 12u;

struct ReducePush {
    uint rd;             // sensor map side
    uint layers;         // layers per sensor: main, then a zoom pair per light group
    uint main_layers;    // summed with the precomputed weights
    uint atlas_columns;  // 0: maps are array layers; else tiles of one atlas, this many per row
    uint groups;         // light groups measured (0: the paper's estimator)
    uint chunks;         // emitter chunks of the scene: the stride of the irradiance per sensor
    float emission_scale;  // emitter-front texels (alpha > 0) are multiplied by it (the maps' Ke scale)
    uint main_entries;   // 1: the main layers hold cache entries (CACHE_ENTRIES), no light: they add nothing
};

// The transport rows' pass (src/passes/transport.rs, transport.comp).
struct TransportPush {
    uint rd;             // sensor map side
    uint layers;         // layers per sensor
    uint main_layers;    // the layers copied
    uint atlas_columns;  // 0: maps are array layers; else tiles of one atlas, this many per row
};

// A texel that sees no surface, in transport.comp's texel list.
const uint TRANSPORT_NONE = 0xffffffffu;

// Bilinear fill of [x0, own_x1] x [y0, own_y1] from the sensed corners (x0|x1, y0|y1).
struct GpuQuad {
    uint x0;
    uint y0;
    uint x1;
    uint y1;
    uint own_x1;
    uint own_y1;
    uint _pad[2];
};

struct ImagePush {
    uint width;
    uint height;
    uint radius;  // filter radius
    uint count;   // number of quads
};

// Composition (src/gpu_types.rs ComposePush): no-surface pixels show the background.
struct ComposePush {
    vec4 background;  // rgb: radiance of rays that leave the scene (no sky map)
    uint width;
    uint height;
    uint apart;       // 1: the indirect part was filtered apart
    uint sky;         // 1: a pixel without a surface shows its own sky (sky_pixels)
};

// The sky map (src/gpu_types.rs GpuSky): levels = 0 for none.
struct GpuSky {
    uint width;
    uint height;
    uint levels;
    uint _pad;
    vec4 rotation;  // cos, sin of its turn about +y
};

// Surface id of pixels where no surface is seen (src/scene/mod.rs NO_SURFACE).
const uint NO_SURFACE = 0u;

// Interpolation with the emitters' light computed per pixel (src/gpu_types.rs ExactInterpolatePush).
struct ExactInterpolatePush {
    uint width;
    uint count;   // number of pixels to fill
    uint groups;  // light groups
    float bias;   // a sensor's lift above its surface, world units
};

// One sub-pixel sample of a supersampled pixel (src/gpu_types.rs GpuSubSample).
struct GpuSubSample {
    vec4 position;  // w: 1 on a surface, 0 where the ray leaves the scene
    vec4 normal;
    vec4 albedo;    // where the ray leaves the scene: the sky it sees
    vec4 own;       // w = 1: its own R less its lights' light (the cache's), instead of a donor's
    uint donor;     // the pixel whose final R the sample takes
    float weight;   // the share of its pixel's square it stands for (supersample/coverage.rs)
    uint _pad[2];
    float visibility[MAX_GROUPS];        // at the sample (< 0: not measured)
    float donor_visibility[MAX_GROUPS];  // at the donor
};

// A supersampled pixel (src/gpu_types.rs GpuSupersampledPixel).
struct GpuSupersampledPixel {
    vec4 emission;  // rgb: the mean radiance its square emits (exact)
    uint pixel;
    uint _pad[3];
};

// The supersampling's resolve (src/gpu_types.rs ResolvePush).
struct ResolvePush {
    uint width;
    uint count;    // supersampled pixels
    uint samples;  // sub-samples per pixel
    uint groups;
    float bias;
    uint exact;    // 1: the light groups' light computed at each sample
    uint _pad[2];
};

// w of the radiance map: how R was obtained (src/gpu_types.rs radiance_state).
const float STATE_NONE = 0.0;
const float STATE_SENSED = 1.0;
const float STATE_INTERPOLATED = 2.0;

const float PI = 3.14159265358979323846;

// One cluster of the LOD hierarchy (clusters::Cluster flattened).
struct GpuCluster {
    vec4 sphere;      // bounding sphere of its triangles
    vec4 slab;        // the slab holding them: unit axis, half thickness about the sphere's centre
    vec4 box_min;     // the box of its triangles (xyz; w unused)
    vec4 box_max;
    vec4 own_min;     // its own error bound's box; w: its error (0: full detail)
    vec4 own_max;
    vec4 parent_min;  // its parent's; w: its error (FLT_MAX: terminal)
    vec4 parent_max;
    uint first_index;
    uint index_count;
    uint flags;  // CLUSTER_EMITTER | CLUSTER_CLOSED
    uint _pad;
    vec4 part_min;  // the box of its whole part (xyz); outside it a closed part hides its back faces
    vec4 part_max;
};

// One node of the clusters' bounding tree (clusters::TreeNode flattened).
struct GpuCullNode {
    vec4 sphere;      // holds every cluster's bounding sphere below
    vec4 own_min;     // holds their own boxes; w: the smallest own error
    vec4 own_max;
    vec4 parent_min;  // holds their parent boxes; w: the largest parent error
    vec4 parent_max;
    uint first;  // first child node, or with NODE_LEAF first leaf item
    uint count;
    uint flags;  // CLUSTER_EMITTER (an emitter below) | NODE_LEAF
    uint _pad;
};

const uint CLUSTER_EMITTER = 1u;
const uint NODE_LEAF = 2u;
const uint CLUSTER_CLOSED = 4u;
// A kept command's entry (cull.comp → cull_triangles.comp): the eye is outside its closed part.
const uint KEPT_BACK_HIDDEN = 0x80000000u;

// VkDrawIndexedIndirectCommand.
struct GpuDrawCommand {
    uint index_count;
    uint instance_count;
    uint first_index;
    int vertex_offset;
    uint first_instance;  // the view drawn
};

struct CullPush {
    uint views;
    uint per_sensor;
    uint max_per_view;
    uint rd;
    float near;
    uint root;
    uint step;
    uint in_base;
    uint out_base;
    uint out_capacity;
    uint in_capacity;
    uint region;  // the triangle pass: indices in each view's region of the pool (0: no triangle pass)
    uint _pad;
};
#endif
