#version 460
// Sensor maps: each texel stores Ck (paper §III-C) as the vertex shader prepared it for the side seen, and
// in alpha the light group + 1 of an emitter's front (0 otherwise), from which the reduction measures each
// group's visibility. The clear colour is the background radiance, for texels that see no geometry.
//
// With global illumination (push.cache) every surface also returns the light it reflects, read from the
// radiance cache at the point seen (cache.glsl): on an emitter's front divided by the maps' emission scale
// as its Ke is, since the reduction multiplies those texels back.
//
// The CUTOUTS variant, for scenes with cut-outs, discards where a surface is cut out (a shader that may
// discard keeps the depth test from running early, so other scenes do without it).
// variant: CUTOUTS
#include "cache.glsl"
#ifdef CUTOUTS
layout(std430, set = 0, binding = 1) readonly buffer Surfaces { GpuSurface surfaces[]; };
#define TEXTURE_BINDING 6
#include "texture.glsl"
#endif

layout(location = 0) flat in vec3 in_ck_front;
layout(location = 1) flat in vec3 in_ck_back;
layout(location = 2) flat in float in_group;
layout(location = 3) in vec3 in_world;
layout(location = 4) flat in uint in_surface;
layout(location = 5) flat in vec3 in_eye;
#ifdef CUTOUTS
layout(location = 6) in vec2 in_uv;
#endif
layout(location = 0) out vec4 out_ck;

layout(push_constant) uniform Push { SensorPush push; };

void main() {
#ifdef CUTOUTS
    // Cut out as the G-buffer and the ray cast cut (level 0): no light is sent or stopped there.
    GpuSurface s = surfaces[in_surface];
    if (s.alpha_map != 0u && sample_texture(s.alpha_map - 1u, in_uv, 0.0).a < s.alpha_threshold) {
        discard;
    }
#endif
    out_ck = gl_FrontFacing ? vec4(in_ck_front, in_group) : vec4(in_ck_back, 0.0);
    if (push.cache != 0u) {
        vec3 reflected = cached_radiance(in_world, in_eye, in_surface, gl_FrontFacing);
        out_ck.rgb += out_ck.a > 0.0 ? reflected / push.emission_scale : reflected;
    }
}
