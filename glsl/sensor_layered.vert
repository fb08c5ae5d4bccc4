#version 460
// Sensor maps, layered strategy (paper §III-E, DESIGN.md §3 step 3): one instance per sensor view; the
// instance picks the view, and the vertex shader routes the triangle to that view's layer of the 2D-array
// framebuffer with gl_Layer (Vulkan 1.2 shaderOutputLayer). Hemicube side faces are clipped at the horizon
// so that two of them share a layer (see src/sensors/layout.rs).
#extension GL_ARB_shader_viewport_layer_array : require
#include "types.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in uint in_surface;

layout(std430, set = 0, binding = 0) readonly buffer Views { GpuSensorView views[]; };
layout(std430, set = 0, binding = 1) readonly buffer Surfaces { GpuSurface surfaces[]; };
layout(push_constant) uniform Push { SensorPush push; };

// Ck of the triangle's two sides (paper §III-C), chosen per fragment by gl_FrontFacing. Computed here, once
// per vertex, so that the fragment shader touches no memory.
layout(location = 0) flat out vec3 out_ck_front;
layout(location = 1) flat out vec3 out_ck_back;

out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[1];
};

void main() {
    // firstInstance of the draw is the batch's first view.
    GpuSensorView view = views[gl_InstanceIndex];
    vec4 p = vec4(in_position, 1.0);
    gl_Position = view.view_proj * p;
    gl_ClipDistance[0] = dot(view.clip_plane, p);
    gl_Layer = int(view.layer);

    GpuSurface s = surfaces[in_surface];
    out_ck_back = s.kd.rgb * push.epsilon;
    out_ck_front = s.ke.w > 0.0 ? s.ke.rgb : out_ck_back;
}
