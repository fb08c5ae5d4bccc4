#version 460
// Sensor maps: each texel stores Ck (paper §III-C) for the side seen, and in alpha the light group + 1 of
// an emitter's front (0 otherwise), from which the reduction measures each group's visibility: what
// sensor_shade.glsl computes, from the point, surface and view the vertex shader hands on
// (sensor_common.glsl) and both sides' Ck (sensor_sides.glsl). The clear colour is
// the background radiance, for texels that see no geometry (or alpha -1 under a sky map, which the
// reduction looks up along the texel's direction).
//
// The TEXTURES variant, for scenes with textures or cut-outs, reads a surface's texture at the mip level
// the sensor texel covers (uv's screen derivatives) and discards where a surface is cut out (a shader that
// may discard keeps the depth test from running early, so other scenes do without it).
// variant: TEXTURES
#include "types.glsl"
layout(push_constant) uniform Push { SensorPush push; };
layout(std430, set = 0, binding = 0) readonly buffer Views { GpuSensorView views[]; };
layout(std430, set = 0, binding = 1) readonly buffer Surfaces { GpuSurface surfaces[]; };
#ifdef TEXTURES
#define TEXTURE_BINDING 6
#include "texture.glsl"
#endif
#include "sensor_shade.glsl"

layout(location = 0) in vec3 in_world;
layout(location = 1) flat in uint in_surface;
layout(location = 2) flat in uint in_view;
#ifdef TEXTURES
layout(location = 3) in vec2 in_uv;
#endif
layout(location = 0) out vec4 out_ck;

void main() {
    SensorTexel t;
    sensor_sides(surfaces[in_surface], push, t.ck_front, t.ck_back, t.group);
    t.world = in_world;
    t.surface = in_surface;
    // The view matters to the radiance cache only (a uniform branch: no load per texel without it).
    t.eye = vec3(0.0);
    t.zoom = false;
    if (push.cache != CACHE_OFF) {
        GpuSensorView view = views[in_view];
        t.eye = view.eye.xyz;
        t.zoom = (view.flags & VIEW_ZOOM) != 0u;
    }
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
