#version 460
// G-buffer pass: world position, normal turned towards the camera, albedo, emission, surface id.
#include "types.glsl"
#define TEXTURE_BINDING 3
#include "texture.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Surfaces { GpuSurface surfaces[]; };

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;  // the corners' shading normals, interpolated
layout(location = 2) flat in uint in_surface;
layout(location = 3) in vec2 in_uv;

layout(location = 0) out vec4 out_position;  // w = 1 where a surface is seen
layout(location = 1) out vec4 out_normal;    // facing the camera; w = 1 if the front side is seen
layout(location = 2) out vec4 out_albedo;
layout(location = 3) out vec4 out_emission;  // Ke (× its texture) where an emitter's front side is seen
layout(location = 4) out uint out_surface;

void main() {
    GpuSurface s = surfaces[in_surface];
    bool front = gl_FrontFacing;
    vec3 n = normalize(in_normal);
    out_position = vec4(in_position, 1.0);
    out_normal = vec4(front ? n : -n, front ? 1.0 : 0.0);
    // Kd times its texture's mean over the pixel; untextured, Kd.
    vec2 dx = dFdx(in_uv), dy = dFdy(in_uv);
    // A cut-out is tested at the pixel centre (the ray cast's point): the pixel sees the surface or not.
    if (cut_out(s, in_uv)) {
        discard;
    }
    vec3 albedo = s.kd_factor.rgb;
    if (s.kd_map != 0u) {
        albedo *= sample_footprint(s.kd_map - 1u, in_uv, dx, dy).rgb;
    }
    out_albedo = vec4(albedo, 1.0);
    // Ke times its emission texture's mean over the pixel, as the albedo.
    vec3 emission = s.ke.rgb;
    if (s.ke_map != 0u) {
        emission *= sample_footprint(s.ke_map - 1u, in_uv, dx, dy).rgb;
    }
    out_emission = vec4((front && s.ke.w > 0.0) ? emission : vec3(0.0), 1.0);
    out_surface = in_surface;
}
