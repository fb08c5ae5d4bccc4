// What every sensor-map vertex shader does (paper §III-E), whatever the batching strategy: transform by
// the view, clip at the view's planes (hemicube horizon, a frustum sensor's sides for its zoom views; an
// emitters-only view clips everything else), and prepare both sides of the triangle (sensor_shade.glsl's
// `sensor_sides`) so that the fragment shader (sensor.frag) only picks one by gl_FrontFacing.
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
#include "sensor_sides.glsl"

layout(location = 0) flat out vec3 out_ck_front;
layout(location = 1) flat out vec3 out_ck_back;
layout(location = 2) flat out float out_group;  // light group + 1 of an emitter, else 0
layout(location = 3) out vec3 out_world;        // where the texel sees the surface: the cache's key
layout(location = 4) flat out uint out_surface;
layout(location = 5) flat out vec3 out_eye;          // the view's origin
layout(location = 7) flat out uint out_flags;        // the view's VIEW_* flags
#ifdef TEXTURES
layout(location = 6) out vec2 out_uv;  // where the texture and the cut-out are read
#endif

// Clip-space position of this vertex in `view`, its distances to the view's clip planes, and the triangle's
// two sides.
vec4 sensor_vertex(GpuSensorView view, out float clip_distance[4]) {
    vec4 p = vec4(in_position, 1.0);
    for (int k = 0; k < 4; k++) {
        clip_distance[k] = dot(view.clip[k], p);
    }
    GpuSurface s = surfaces[in_surface];
    if ((view.flags & VIEW_EMITTERS_ONLY) != 0u && s.ke.w <= 0.0) {
        clip_distance[0] = -1.0;
    }
    sensor_sides(s, push, out_ck_front, out_ck_back, out_group);
    out_world = in_position;
    out_surface = in_surface;
    out_eye = view.eye.xyz;
    out_flags = view.flags;
#ifdef TEXTURES
    out_uv = (s.kd_map | s.ke_map | s.alpha_map) != 0u ? uvs[gl_VertexIndex] : vec2(0.0);
#endif
    return view.view_proj * p;
}
#endif
