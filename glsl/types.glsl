// Structs shared with Rust: the one mirror of src/gpu_types.rs (std430 and push-constant layout).
// tests/layout.rs compares member offsets and array strides in the compiled SPIR-V with the Rust structs.
#ifndef TYPES_GLSL
#define TYPES_GLSL

// Indexed by surface id; entry 0 is "no surface".
struct GpuSurface {
    vec4 kd;  // albedo Kd (rgb)
    vec4 ke;  // emitted radiance Ke (rgb); w = 1 for an emitter (front face only)
};

struct GBufferPush {
    mat4 view_proj;
};

struct GpuSensorView {
    mat4 view_proj;
    vec4 clip_plane;  // keep dot(clip_plane, vec4(p, 1)) >= 0
    uint layer;       // layer of the sensor-map array
    uint _pad[3];
};

struct SensorPush {
    float epsilon;     // non-emitters return Kd * epsilon (paper eq. 2)
    uint first_view;   // first entry of the view buffer for this draw
    uint _pad[2];
    vec4 background;   // radiance of rays leaving the scene
};

#endif
