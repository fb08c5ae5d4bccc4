// What a sensor texel holds for the surface it sees (paper §III-C), shared by the raster strategies
// (sensor_common.glsl's vertex half, sensor.frag's fragment half) and the compute rasterizer
// (sensor_compute.comp), so that every strategy writes the same Ck:
//   back, or front of a non-emitter: Kd * epsilon;
//   front of an emitter: Ke (the paper's estimator), or 0 and its light group (the exact one, whose
//   emitter light is computed in closed form and only its visibility read from the map);
// with global illumination (push.cache CACHE_VALUES, epsilon 0) the radiance cache's reflected light at the
// point seen, on either side; with CACHE_ENTRIES instead of any light, which of the cache's values that is
// (the radiance cache's transport, src/gi/transport.rs). With TEXTURES the including shader declares `surfaces` and the texture bindings
// (texture.glsl).
#ifndef SENSOR_SHADE_GLSL
#define SENSOR_SHADE_GLSL
#include "cache.glsl"
#include "sensor_sides.glsl"

// One texel seen by a sensor: the side seen, where, from where, and (TEXTURES) the texture coordinates and
// their steps to the next texel along x and y.
struct SensorTexel {
    vec3 ck_front;
    vec3 ck_back;
    float group;
    vec3 world;
    uint surface;
    vec3 eye;
    bool front_facing;
    bool zoom;  // in a zoom view, whose texels are read only for their light group
    vec2 uv;
    vec2 dx;
    vec2 dy;
};

// The texel's value (rgb: Ck, alpha: an emitter front's group + 1, else 0); false where the surface is cut
// out there (no light is sent or stopped: the texel shows what lies behind).
bool sensor_shade(SensorTexel t, SensorPush p, out vec4 ck) {
    // What the surface reflects relative to its mean albedo (which Kd·ε and the cache's values carry).
    vec3 scale = vec3(1.0);
    ck = vec4(0.0);
#ifdef TEXTURES
    GpuSurface s = surfaces[t.surface];
    // Cut out as the G-buffer and the ray cast cut (level 0).
    if (cut_out(s, t.uv)) {
        return false;
    }
    if (s.kd_map != 0u) {
        uint map = s.kd_map - 1u;
        vec3 albedo = s.kd_factor.rgb * sample_texture(map, t.uv, texture_lod(map, t.dx, t.dy)).rgb;
        scale = mix(vec3(1.0), albedo / max(s.kd.rgb, vec3(1e-6)), greaterThan(s.kd.rgb, vec3(0.0)));
    }
#endif
    // An emitter's front as prepared; any other side reflects, Kd·ε × scale.
    bool emitter_front = t.front_facing && t.group > 0.0;
    vec3 front = t.ck_front;
#ifdef TEXTURES
    // The paper's estimator sees the emission texture at the texel's level (the exact one's Ck is 0 here).
    if (emitter_front && s.ke_map != 0u) {
        uint map = s.ke_map - 1u;
        front *= sample_texture(map, t.uv, texture_lod(map, t.dx, t.dy)).rgb;
    }
#endif
    ck = emitter_front ? vec4(front, t.group) : vec4((t.front_facing ? front : t.ck_back) * scale, 0.0);
    if (t.zoom) {
        // Only the light groups are read here: no cache.
    } else if (p.cache == CACHE_ENTRIES) {
        // Which value the texel reads, in three channels of CACHE_ENTRY_BITS (integers below 2048 are exact
        // in half floats); emitter fronts keep their group for the zoom views' visibilities.
        uint v = cache_lookup(t.world, t.eye, t.surface, t.front_facing);
        uint mask = (1u << CACHE_ENTRY_BITS) - 1u;
        vec3 digits = vec3(uvec3(v, v >> CACHE_ENTRY_BITS, v >> (2u * CACHE_ENTRY_BITS)) & mask);
        ck = vec4(digits, ck.a > 0.0 ? ck.a : CACHE_ENTRY_MARK);
    } else if (p.cache == CACHE_VALUES) {
        vec3 reflected = cached_radiance(t.world, t.eye, t.surface, t.front_facing) * scale;
        ck.rgb += ck.a > 0.0 ? reflected / p.emission_scale : reflected;
    }
    return true;
}
#endif
