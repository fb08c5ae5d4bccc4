#version 460
// Sensor maps: each texel stores Ck (paper §III-C) as the vertex shader prepared it for the side seen, and
// in alpha the light group + 1 of an emitter's front (0 otherwise), from which the reduction measures each
// group's visibility. The clear colour is the background radiance, for texels that see no geometry (or
// alpha -1 under a sky map, which the reduction looks up along the texel's direction).
//
// With global illumination (push.cache) every surface also returns the light it reflects, read from the
// radiance cache at the point seen (cache.glsl): on an emitter's front divided by the maps' emission scale
// as its Ke is, since the reduction multiplies those texels back.
//
// The TEXTURES variant, for scenes with textures or cut-outs, reads a surface's texture at the mip level
// the sensor texel covers (Kd·ε and the cache's light scaled from the surface's mean albedo to the texel's),
// multiplies an emitter's front by its emission texture, and discards where a surface is cut out (a shader
// that may discard keeps the depth test from running early, so other scenes do without it).
// variant: TEXTURES
#include "cache.glsl"
#ifdef TEXTURES
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
#ifdef TEXTURES
layout(location = 6) in vec2 in_uv;
#endif
layout(location = 0) out vec4 out_ck;

layout(push_constant) uniform Push { SensorPush push; };

void main() {
    // What the surface reflects relative to its mean albedo (which Kd·ε and the cache's values carry).
    vec3 scale = vec3(1.0);
#ifdef TEXTURES
    vec2 dx = dFdx(in_uv), dy = dFdy(in_uv);
    GpuSurface s = surfaces[in_surface];
    // Cut out as the G-buffer and the ray cast cut (level 0): no light is sent or stopped there.
    if (cut_out(s, in_uv)) {
        discard;
    }
    if (s.kd_map != 0u) {
        uint map = s.kd_map - 1u;
        vec3 albedo = s.kd_factor.rgb * sample_texture(map, in_uv, texture_lod(map, dx, dy)).rgb;
        scale = mix(vec3(1.0), albedo / max(s.kd.rgb, vec3(1e-6)), greaterThan(s.kd.rgb, vec3(0.0)));
    }
#endif
    // An emitter's front as the vertex shader prepared it; any other side reflects, Kd·ε × scale.
    bool emitter_front = gl_FrontFacing && in_group > 0.0;
    vec3 front = in_ck_front;
#ifdef TEXTURES
    // The paper's estimator sees the emission texture at the texel's level (the exact one's Ck is 0 here).
    if (emitter_front && s.ke_map != 0u) {
        uint map = s.ke_map - 1u;
        front *= sample_texture(map, in_uv, texture_lod(map, dx, dy)).rgb;
    }
#endif
    out_ck = emitter_front ? vec4(front, in_group) : vec4((gl_FrontFacing ? front : in_ck_back) * scale, 0.0);
    if (push.cache != 0u) {
        vec3 reflected = cached_radiance(in_world, in_eye, in_surface, gl_FrontFacing) * scale;
        out_ck.rgb += out_ck.a > 0.0 ? reflected / push.emission_scale : reflected;
    }
}
