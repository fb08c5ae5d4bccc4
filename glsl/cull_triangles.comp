#version 460
// Triangle culling (docs/DESIGN.md §9, passes::cull_triangles), after the culling pass's walk.
// Step 0, one invocation per command the walk wrote (a cluster kept for a view): a triangle stays where it
// may cover a texel centre of the view (may_cover); the survivors' indices go, in their order, to the
// view's region of the slot's index pool, drawn by the view's one command, and the cluster's command
// draws nothing. Where the region is full the cluster's command keeps it whole.
// Step 1, one invocation per view: its cluster list is drawn only where a cluster was left whole.
// A cluster whose entry carries KEPT_BACK_HIDDEN (its closed part seen from outside: cull.comp) also drops
// the triangles that turn their backs to the eye, which its front faces hide.
// CPU twin: passes::cull_triangles::{may_cover, faces}.
#include "types.glsl"

// One invocation per cluster, which tests its triangles in turn: on a CPU rasterizer a workgroup barrier
// switches every invocation's coroutine, which cost more than the triangles (a workgroup per cluster with
// a prefix sum in shared memory made the Cornell box's sensor 2.2 times as costly).
const uint GROUP = 64u;
layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Views { GpuSensorView views[]; };
// The clusters' vertices (position, surface) and indices, and the slot's pool: a region per view.
layout(std430, set = 0, binding = 1) readonly buffer Vertices { vec4 vertices[]; };
layout(std430, set = 0, binding = 2) readonly buffer Indices { uint indices[]; };
layout(std430, set = 0, binding = 7) writeonly buffer Pool { uint pool[]; };
// Each view's count of region draws, 1 or 0 (step 1), for drawIndirectCount: lavapipe (Mesa 25.0)
// carries a count-buffer draw's count over to a plain indirect draw recorded after it.
layout(std430, set = 0, binding = 8) writeonly buffer RegionDraws { uint region_draws[]; };
layout(std430, set = 0, binding = 3) buffer Commands { GpuDrawCommand commands[]; };
// Blocks of `views` u32 (passes::cull): the list's draws, triangles selected, triangles drawn, indices
// reserved in the view's region, clusters left whole, the walk's draws.
layout(std430, set = 0, binding = 4) buffer Counts { uint counts[]; };
// What the walk kept: (commands, workgroups, 1, 1), a VkDispatchIndirectCommand in yzw, then each
// command's index.
layout(std430, set = 0, binding = 5) buffer Kept { uvec4 kept_dispatch; uint kept[]; };
// Each view's command over its region of the pool (the walk's first step starts them).
layout(std430, set = 0, binding = 6) buffer Regions { GpuDrawCommand regions[]; };
layout(push_constant) uniform Push { CullPush push; };

// COVER_SLACK: the rasterizer snaps to 1/256 texel, and the vertex shader may round differently.
const float SLACK = 1.0 / 64.0;

// Whether [lo, hi] (window coordinates, widened by SLACK) holds a texel centre k + 0.5.
bool holds_centre(float lo, float hi) {
    return floor(hi - 0.5 + SLACK) >= ceil(lo - 0.5 - SLACK);
}

bool outside(vec3 d) {
    return all(lessThan(d, vec3(0.0)));
}

// cull_triangles::may_cover: false only where no fragment of the triangle can be rasterized in `view`.
bool may_cover(GpuSensorView view, vec3 p0, vec3 p1, vec3 p2) {
    for (int k = 0; k < 4; k++) {
        vec4 plane = view.clip[k];
        if (outside(vec3(dot(plane.xyz, p0), dot(plane.xyz, p1), dot(plane.xyz, p2)) + plane.w)) {
            return false;
        }
    }
    vec4 c0 = view.view_proj * vec4(p0, 1.0);
    vec4 c1 = view.view_proj * vec4(p1, 1.0);
    vec4 c2 = view.view_proj * vec4(p2, 1.0);
    vec3 x = vec3(c0.x, c1.x, c2.x);
    vec3 y = vec3(c0.y, c1.y, c2.y);
    vec3 z = vec3(c0.z, c1.z, c2.z);
    vec3 w = vec3(c0.w, c1.w, c2.w);
    if (outside(w - x) || outside(w + x) || outside(w - y) || outside(w + y) || outside(w - z)) {
        return false;
    }
    if (any(lessThanEqual(w, vec3(0.0)))) {
        return true;
    }
    float size = float(push.rd);
    vec2 s0 = (c0.xy / c0.w * 0.5 + 0.5) * size;
    vec2 s1 = (c1.xy / c1.w * 0.5 + 0.5) * size;
    vec2 s2 = (c2.xy / c2.w * 0.5 + 0.5) * size;
    vec2 lo = min(min(s0, s1), s2);
    vec2 hi = max(max(s0, s1), s2);
    return holds_centre(lo.x, hi.x) && holds_centre(lo.y, hi.y);
}

// cull_triangles::faces: whether the triangle turns its front (counter-clockwise) towards `eye`.
bool faces(vec3 eye, vec3 p0, vec3 p1, vec3 p2) {
    return dot(cross(p1 - p0, p2 - p0), eye - p0) > 0.0;
}

// Step 1: a view's cluster list draws where a cluster was left whole; its walk's count kept for the host.
void finish() {
    uint v = gl_GlobalInvocationID.x;
    if (v < push.views) {
        uint n = push.views;
        region_draws[v] = regions[v].index_count > 0u ? 1u : 0u;
        counts[5u * n + v] = counts[v];
        if (counts[4u * n + v] == 0u) {
            counts[v] = 0u;
        }
    }
}

void main() {
    if (push.step == 1u) {
        finish();
        return;
    }
    uint n_views = push.views;
    uint total = kept_dispatch.x;
    for (uint k = gl_GlobalInvocationID.x; k < total; k += gl_NumWorkGroups.x * GROUP) {
        uint command = kept[k] & ~KEPT_BACK_HIDDEN;
        bool back_hidden = (kept[k] & KEPT_BACK_HIDDEN) != 0u;
        uint v = command / push.max_per_view;
        GpuSensorView view = views[v];
        GpuDrawCommand draw = commands[command];
        uint n = draw.index_count / 3u;
        // clusters::build::MAX_TRIANGLES, which `keep` has a bit for each of: a larger cluster stays whole.
        bool testable = n <= 128u;
        // Which triangles stay, a bit each, and how many.
        uint keep[4] = uint[4](0u, 0u, 0u, 0u);
        uint survivors = 0u;
        for (uint t = 0u; testable && t < n; t++) {
            uint first = draw.first_index + 3u * t;
            vec3 p0 = vertices[indices[first]].xyz;
            vec3 p1 = vertices[indices[first + 1u]].xyz;
            vec3 p2 = vertices[indices[first + 2u]].xyz;
            if ((!back_hidden || faces(view.eye.xyz, p0, p1, p2)) && may_cover(view, p0, p1, p2)) {
                keep[t >> 5u] |= 1u << (t & 31u);
                survivors++;
            }
        }
        uint base = survivors == 0u ? 0u : atomicAdd(counts[3u * n_views + v], 3u * survivors);
        bool fits = testable && base + 3u * survivors <= push.region;
        if (fits) {
            uint at = v * push.region + base;
            for (uint t = 0u; t < n; t++) {
                if ((keep[t >> 5u] & (1u << (t & 31u))) != 0u) {
                    uint first = draw.first_index + 3u * t;
                    pool[at] = indices[first];
                    pool[at + 1u] = indices[first + 1u];
                    pool[at + 2u] = indices[first + 2u];
                    at += 3u;
                }
            }
            commands[command].index_count = 0u;
            atomicAdd(regions[v].index_count, 3u * survivors);
        } else {
            atomicAdd(counts[4u * n_views + v], 1u);
        }
        atomicAdd(counts[2u * n_views + v], fits ? survivors : n);
    }
}
