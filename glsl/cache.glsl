// The radiance cache as the sensor maps see it (docs/DESIGN.md §10, src/gi): a fragment's reflected light
// is the entry of its side of its surface's piece of its cell, found by the key and hash src/gi/grid.rs
// computes the same way, then, where walls cut the piece, by the side of each splitting plane it lies on.
// The table is open addressing with linear probing, at most half full; a key it lacks (none should: every
// cell a surface's triangles reach has one) reads the surface side's area-weighted mean.
#ifndef CACHE_GLSL
#define CACHE_GLSL
#include "types.glsl"

layout(std430, set = 0, binding = 2) readonly buffer CacheTable {
    GpuCacheGrid cache_grid;
    GpuCacheSlot cache_slots[];
};
layout(std430, set = 0, binding = 3) readonly buffer CacheValues { vec4 cache_values[]; };
layout(std430, set = 0, binding = 4) readonly buffer CacheSplits { GpuCacheSplit cache_splits[]; };

// src/gi/grid.rs `hash`.
uint cache_hash(uvec2 key) {
    uint h = (key.x * 0x9e3779b1u) ^ (key.y * 0x85ebca77u);
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    return h ^ (h >> 16);
}

// How far towards the eye a fragment is moved to decide which side of a split plane it lies on, relative
// to its distance (src/gi/mod.rs SPLIT_PULL).
const float CACHE_SPLIT_PULL = 1e-3;

// The value index for a point `p` on side `front` of `surface`, seen from `eye` (src/gi/mod.rs `lookup`).
// A fragment where a wall meets a surface that runs on beyond it (one floor under two rooms) interpolates
// a position a rounding error past the wall's plane, where the piece is split: seen from the near side, it
// is classified a little towards the eye, on the side the eye is.
uint cache_lookup(vec3 p, vec3 eye, uint surface, bool front) {
    ivec3 c = ivec3(floor((p - cache_grid.origin.xyz) * cache_grid.origin.w));
    uvec3 cell = uvec3(clamp(c, ivec3(0), ivec3(cache_grid.dims.xyz) - 1));
    uvec2 key = uvec2(cell.x | (cell.y << 10) | (cell.z << 20), surface);
    uint mask = cache_grid.dims.w;
    uint i = cache_hash(key) & mask;
    uint side = front ? 1u : 0u;
    // At most half full, so an empty slot ends every probe; the bounds only guard against a damaged table.
    for (uint n = 0u; n <= mask; n++) {
        GpuCacheSlot slot = cache_slots[i];
        if (slot.key.y == 0u) {
            break;
        }
        if (slot.key == key) {
            uint reference = slot.entry;
            vec3 q = mix(p, eye, CACHE_SPLIT_PULL);
            for (uint depth = 0u; depth < CACHE_SPLIT_DEPTH && (reference & CACHE_SPLIT) != 0u; depth++) {
                GpuCacheSplit split = cache_splits[reference & ~CACHE_SPLIT];
                reference = dot(split.plane.xyz, q) + split.plane.w >= 0.0 ? split.children.y : split.children.x;
            }
            return 2u * reference + side;
        }
        i = (i + 1u) & mask;
    }
    return cache_grid.entries + 2u * surface + side;
}

vec3 cached_radiance(vec3 p, vec3 eye, uint surface, bool front) {
    return cache_values[cache_lookup(p, eye, surface, front)].rgb;
}
#endif
