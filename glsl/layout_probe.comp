#version 460
// Not a pass: exists so that tests/layout.rs can read the std430 layout of every shared struct out of
// compiled SPIR-V (member offsets, array strides) and compare it with src/gpu_types.rs.
#include "types.glsl"

layout(local_size_x = 1) in;

layout(std430, set = 0, binding = 0) buffer Surfaces { GpuSurface surfaces[]; };
layout(std430, set = 0, binding = 1) buffer GBufferPushes { GBufferPush gbuffer_pushes[]; };
layout(std430, set = 0, binding = 2) buffer SensorViews { GpuSensorView sensor_views[]; };
layout(std430, set = 0, binding = 3) buffer SensorPushes { SensorPush sensor_pushes[]; };

void main() {
    // Touch every array so the compiler keeps the types.
    surfaces[1] = surfaces[0];
    gbuffer_pushes[1] = gbuffer_pushes[0];
    sensor_views[1] = sensor_views[0];
    sensor_pushes[1] = sensor_pushes[0];
}
