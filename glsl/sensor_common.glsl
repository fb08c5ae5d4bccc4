// What every sensor-map vertex shader does (paper §III-E), whatever the batching strategy: transform by
// the view, clip at the view's plane (hemicube horizon), and prepare Ck of both sides of the triangle
// (paper §III-C) so that the fragment shader (sensor.frag) only picks one by gl_FrontFacing.
#ifndef SENSOR_COMMON_GLSL
#define SENSOR_COMMON_GLSL
#include "types.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in uint in_surface;

layout(std430, set = 0, binding = 0) readonly buffer Views { GpuSensorView views[]; };
layout(std430, set = 0, binding = 1) readonly buffer Surfaces { GpuSurface surfaces[]; };
layout(push_constant) uniform Push { SensorPush push; };

layout(location = 0) flat out vec3 out_ck_front;
layout(location = 1) flat out vec3 out_ck_back;

// Clip-space position of this vertex in `view`, and Ck of its triangle's two sides.
vec4 sensor_vertex(GpuSensorView view, out float horizon_distance) {
    vec4 p = vec4(in_position, 1.0);
    horizon_distance = dot(view.clip_plane, p);
    GpuSurface s = surfaces[in_surface];
    out_ck_back = s.kd.rgb * push.epsilon;
    out_ck_front = s.ke.w > 0.0 ? s.ke.rgb : out_ck_back;
    return view.view_proj * p;
}
#endif
