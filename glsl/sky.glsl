// The sky map as the reduction reads it: the GPU twin of src/scene/sky.rs (`SkyMap::radiance_lod`), from the
// same levels (linear RGB, level 0 first, each level row by row from the zenith). The includer binds the
// map's description (a GpuSky: levels = 0 for no map) and its texels at SKY_BINDING and SKY_BINDING + 1 of
// set 0.
#ifndef SKY_GLSL
#define SKY_GLSL
#include "types.glsl"

layout(std430, set = 0, binding = SKY_BINDING) readonly buffer SkyTable { GpuSky sky_map; };
layout(std430, set = 0, binding = SKY_BINDING + 1) readonly buffer SkyTexels { vec4 sky_texels[]; };

// Texture coordinates of the unit direction d, the map turned about +y: u = atan2(x, -z) / 2pi wrapped,
// v = acos(y) / pi of d turned back.
vec2 sky_uv(vec3 d) {
    vec2 r = sky_map.rotation.xy;
    d = vec3(r.x * d.x - r.y * d.z, d.y, r.y * d.x + r.x * d.z);
    float u = atan(d.x, -d.z) / (2.0 * PI);
    return vec2(u - floor(u), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

// Level `level`'s first texel and size.
uint sky_level(uint level, out ivec2 size) {
    uint offset = 0u;
    size = ivec2(sky_map.width, sky_map.height);
    for (uint l = 0u; l < level; l++) {
        offset += uint(size.x * size.y);
        size = max(size / 2, ivec2(1));
    }
    return offset;
}

// Bilinear within the level at `offset` of `size`: texel centres at half-integers, u wrapping, v clamped.
vec3 sky_bilinear(uint offset, ivec2 size, vec2 uv) {
    float x = (uv.x - floor(uv.x)) * float(size.x) - 0.5;
    float y = clamp(clamp(uv.y, 0.0, 1.0) * float(size.y) - 0.5, 0.0, float(size.y - 1));
    vec2 base = floor(vec2(x, y));
    vec2 f = vec2(x, y) - base;
    ivec2 i = ivec2(base);
    vec3 c[4];
    for (int k = 0; k < 4; k++) {
        ivec2 at = i + ivec2(k & 1, k >> 1);
        at = ivec2(((at.x % size.x) + size.x) % size.x, min(at.y, size.y - 1));
        c[k] = sky_texels[offset + uint(at.y * size.x + at.x)].rgb;
    }
    return mix(mix(c[0], c[1], f.x), mix(c[2], c[3], f.x), f.y);
}

// The radiance from the unit direction d averaged over about `solid_angle` steradians: on the level whose
// texels at the horizon are that large (SkyMap::lod), blending the two levels around it.
vec3 sky_radiance(vec3 d, float solid_angle) {
    float texel = 2.0 * PI * PI / float(sky_map.width * sky_map.height);
    float lod = clamp(0.5 * log2(max(solid_angle / texel, 1.0)), 0.0, float(sky_map.levels - 1u));
    float lower = floor(lod);
    vec2 uv = sky_uv(d);
    ivec2 size;
    uint offset = sky_level(uint(lower), size);
    vec3 a = sky_bilinear(offset, size, uv);
    if (lod == lower) {
        return a;
    }
    // The next level, one step further.
    offset += uint(size.x * size.y);
    size = max(size / 2, ivec2(1));
    return mix(a, sky_bilinear(offset, size, uv), lod - lower);
}
#endif
