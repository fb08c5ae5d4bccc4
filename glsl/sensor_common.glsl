// What every sensor-map vertex shader does (paper §III-E), whatever the batching strategy: transform by
// the view, clip at the view's planes (hemicube horizon, a frustum sensor's sides for its zoom views; an
// emitters-only view clips everything else), and hand the fragment shader (sensor.frag) the point, its
// surface and its view.
#ifndef SENSOR_COMMON_GLSL
#define SENSOR_COMMON_GLSL
#include "types.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in uint in_surface;

layout(std430, set = 0, binding = 0) readonly buffer Views { GpuSensorView views[]; };
layout(std430, set = 0, binding = 1) readonly buffer Surfaces { GpuSurface surfaces[]; };
#ifdef TEXTURES
// Texture coordinates per vertex (of the soup, or of the clusters where drawn from them): read for a
// surface with a texture or a cut-out only (elsewhere the buffer may hold a placeholder).
layout(std430, set = 0, binding = 5) readonly buffer Uvs { vec2 uvs[]; };
#endif
layout(push_constant) uniform Push { SensorPush push; };

// Drawn from the culling pass's per-view lists, each draw is one view, named in the push constants: a value
// the whole draw shares, whose view a CPU rasterizer loads once, where it loads `views[gl_InstanceIndex]`
// vertex by vertex (lavapipe: a sensor in a real interior 0.75× as costly, docs/BENCHMARKS.md). Drawn
// whole, one instanced draw covers many views, the instance naming each.
layout(constant_id = 0) const bool VIEW_PER_DRAW = false;

// The view this vertex is drawn in, for the layered and atlas strategies (multiview names its own).
uint draw_view() {
    return VIEW_PER_DRAW ? push.first_view : uint(gl_InstanceIndex);
}

// Only what varies across a triangle or names it: the fragment shader reads the rest (both sides' Ck, the
// view's eye and flags) from `surfaces` and `views` itself. On a CPU rasterizer every output costs setup
// and binning per triangle, and a sensor draws thousands of triangles over few texels.
layout(location = 0) out vec3 out_world;  // where the texel sees the surface: the cache's key
layout(location = 1) flat out uint out_surface;
layout(location = 2) flat out uint out_view;  // index into `views`
#ifdef TEXTURES
layout(location = 3) out vec2 out_uv;  // where the texture and the cut-out are read
#endif

// Clip-space position of this vertex in view `view_index`, and its distances to the view's clip planes.
vec4 sensor_vertex(uint view_index, out float clip_distance[4]) {
    GpuSensorView view = views[view_index];
    vec4 p = vec4(in_position, 1.0);
    for (int k = 0; k < 4; k++) {
        clip_distance[k] = dot(view.clip[k], p);
    }
    GpuSurface s = surfaces[in_surface];
    if ((view.flags & VIEW_EMITTERS_ONLY) != 0u && s.ke.w <= 0.0) {
        clip_distance[0] = -1.0;
    }
    out_world = in_position;
    out_surface = in_surface;
    out_view = view_index;
#ifdef TEXTURES
    out_uv = (s.kd_map | s.ke_map | s.alpha_map) != 0u ? uvs[gl_VertexIndex] : vec2(0.0);
#endif
    return view.view_proj * p;
}
#endif
