#version 460
// Sensor maps: each texel stores Ck (paper §III-C) for the side seen, and in alpha the light group + 1 of
// an emitter's front (0 otherwise), from which the reduction measures each group's visibility: what
// sensor_shade.glsl computes, from what the vertex shader prepared (sensor_common.glsl). The clear colour is
// the background radiance, for texels that see no geometry (or alpha -1 under a sky map, which the
// reduction looks up along the texel's direction).
//
// The TEXTURES variant, for scenes with textures or cut-outs, reads a surface's texture at the mip level
// the sensor texel covers (uv's screen derivatives) and discards where a surface is cut out (a shader that
// may discard keeps the depth test from running early, so other scenes do without it).
// variant: TEXTURES
#include "types.glsl"
layout(push_constant) uniform Push { SensorPush push; };
#ifdef TEXTURES
layout(std430, set = 0, binding = 1) readonly buffer Surfaces { GpuSurface surfaces[]; };
#define TEXTURE_BINDING 6
#include "texture.glsl"
#endif
#include "sensor_shade.glsl"

layout(location = 0) flat in vec3 in_ck_front;
layout(location = 1) flat in vec3 in_ck_back;
layout(location = 2) flat in float in_group;
layout(location = 3) in vec3 in_world;
layout(location = 4) flat in uint in_surface;
layout(location = 5) flat in vec3 in_eye;
layout(location = 7) flat in uint in_flags;
#ifdef TEXTURES
layout(location = 6) in vec2 in_uv;
#endif
layout(location = 0) out vec4 out_ck;

void main() {
    SensorTexel t;
    t.ck_front = in_ck_front;
    t.ck_back = in_ck_back;
    t.group = in_group;
    t.world = in_world;
    t.surface = in_surface;
    t.eye = in_eye;
    t.zoom = (in_flags & VIEW_ZOOM) != 0u;
    t.front_facing = gl_FrontFacing;
#ifdef TEXTURES
    t.uv = in_uv;
    t.dx = dFdx(in_uv);
    t.dy = dFdy(in_uv);
#endif
    if (!sensor_shade(t, push, out_ck)) {
        discard;
    }
}
