// Ck of both sides of a triangle (paper §III-C), flat across it: what the raster strategies' fragment
// shader (sensor.frag) and the compute rasterizer (sensor_compute.comp) prepare for sensor_shade.glsl to
// pick from by the side seen.
#ifndef SENSOR_SIDES_GLSL
#define SENSOR_SIDES_GLSL
#include "types.glsl"

// Both sides of a triangle of surface `s` (flat across it): Ck of its front, of its back, and its light
// group + 1 where it emits (else 0).
void sensor_sides(GpuSurface s, SensorPush p, out vec3 front, out vec3 back, out float group) {
    bool emitter = s.ke.w > 0.0;
    back = s.kd.rgb * p.epsilon;
    front = emitter ? (p.exact != 0u ? vec3(0.0) : s.ke.rgb / p.emission_scale) : back;
    group = emitter ? s.ke.w : 0.0;
}
#endif
