#version 460
// Compute strategy (src/passes/sensor_maps/compute.rs): the batch's sensor maps rasterized by compute
// shaders, one workgroup per map layer, into the same 2D-array image the graphics strategies draw.
//
//   layer L of the batch ─▶ workgroup L:  for each tile of TILE² texels of the layer (one tile up to rd 32):
//     for each view drawing into L (a hemicube side layer holds two half views), for each chunk of GROUP
//     triangles (the whole soup, or the view's culled draw list, paper §9 clusters):
//       set-up:  invocation i transforms triangle i of the chunk, keeps its homogeneous edge functions
//                and depth plane in shared memory, and finds its span in each row of the tile it
//                reaches (s_span: one row's span is found once, not by every invocation of the row); ── barrier
//       raster:  every invocation depth-tests the chunk's triangles at the texels it owns (TILE² / GROUP
//                each) inside their spans, keeping the nearest in registers: no atomics, no shared depth
//                buffer;                                                                  ── barrier
//
//   s_span, a row's span of each triangle of the chunk (TILE words per triangle, rows the triangle's
//   box misses unwritten):
//     triangle 0: [row 0][row 1] … [row TILE-1]   word = (first texel + 1) | (last texel + 1) << 16
//     triangle 1: [row 0][row 1] … [row TILE-1]   (empty: first > last)
//     …
//     shade: each invocation writes Ck of its texels' nearest triangle (sensor_shade.glsl), or the clear.
//
// Rasterization as Vulkan's: texel centres sampled, the top-left fill rule, reversed-Z depth tested GREATER
// in drawing order (the first of equal depths kept), the view's clip planes (hemicube horizon, half sides,
// zoom views), front faces counter-clockwise in framebuffer space. Coverage is tested with 2D
// homogeneous edge functions (Olano & Greer 1997): λ = N⁻¹·(x, y, 1) for N the clip-space (X, Y, W)
// columns of the corners; a texel centre is inside when every λᵢ ≥ 0 and Σλ > 0 (then 1/Σλ is its W > 0),
// so no triangle is clipped, even one crossing the eye's plane; λ/Σλ are its perspective-correct
// barycentric coordinates and λ·Z its depth. Along a row each of these tests is linear in the texel, so
// a triangle's texels in a row are one span (`set_up`). Unlike the hardware, the corners are not snapped
// to 1/256 of a texel: an edge that passes within that of a texel centre may be decided otherwise, so the
// maps are not bit-identical to the graphics strategies' (docs/DESIGN.md §5).
// variant: TEXTURES
#include "types.glsl"

const uint GROUP = 128u;  // invocations per workgroup, and triangles per chunk
const uint TILE = 32u;    // texels per side of the part of a layer held at once
const uint PER_INVOCATION = TILE * TILE / GROUP;

layout(local_size_x = GROUP) in;

layout(push_constant) uniform Push { SensorComputePush push; };

layout(std430, set = 0, binding = 0) readonly buffer Views { GpuSensorView views[]; };
layout(std430, set = 0, binding = 1) readonly buffer Surfaces { GpuSurface surfaces[]; };
#ifdef TEXTURES
layout(std430, set = 0, binding = 5) readonly buffer Uvs { vec2 uvs[]; };
#define TEXTURE_BINDING 6
#include "texture.glsl"
#endif
#include "sensor_shade.glsl"
// The soup's or the clusters' vertices (`gpu_types::Vertex`: position, surface id as bits in w).
layout(std430, set = 0, binding = 8) readonly buffer Vertices { vec4 vertices[]; };
// Culled: the clusters' index buffer, each view's draw list and the lists' lengths (passes::cull).
layout(std430, set = 0, binding = 9) readonly buffer Indices { uint indices[]; };
layout(std430, set = 0, binding = 10) readonly buffer Commands { GpuDrawCommand commands[]; };
layout(std430, set = 0, binding = 11) readonly buffer Counts { uint counts[]; };
layout(set = 0, binding = 12, rgba16f) uniform writeonly image2DArray maps;

// The chunk's triangles after set-up. An empty box (x > z) marks no triangle.
shared mat3 s_edges[GROUP];      // N⁻¹: λ = s_edges · (x, y, 1)
shared vec3 s_depth[GROUP];      // clip z of the corners: depth = λ · s_depth
shared ivec4 s_box[GROUP];       // texels of the tile it may cover: min x, min y, max x, max y (inclusive)
shared uvec4 s_corners[GROUP];   // vertex indices, and the view's index in the view buffer
shared uint s_span[GROUP * TILE];  // its texels in each row of the tile (see the diagram above)

// Nearest triangle so far at each texel this invocation owns (0: none; depths are > 0).
float best_depth[PER_INVOCATION];
uvec4 best_corners[PER_INVOCATION];

// Texel centre (x, y) of the layer in normalized device coordinates (Vulkan: y down, row 0 at -1).
vec3 ndc(ivec2 texel) {
    return vec3((vec2(texel) + 0.5) * (2.0 / float(push.rd)) - 1.0, 1.0);
}

// Clip-space (X, Y, W) of the corners as columns, their clip z and world positions.
mat3 corners_in_view(GpuSensorView view, uvec3 c, out vec3 z, out mat3 world) {
    mat3 n;
    for (int i = 0; i < 3; i++) {
        world[i] = vertices[c[i]].xyz;
        vec4 h = view.view_proj * vec4(world[i], 1.0);
        n[i] = h.xyw;
        z[i] = h.z;
    }
    return n;
}

#ifdef TEXTURES
// Texture coordinates at barycentric `b` of the triangle with corners `c`.
vec2 uv_at(uvec3 c, vec3 b) {
    return b.x * uvs[c.x] + b.y * uvs[c.y] + b.z * uvs[c.z];
}
#endif

// Perspective-correct barycentric coordinates at the centre of `texel` (on the triangle's plane, inside
// the triangle or not) of the triangle whose N⁻¹ is `edges`.
vec3 barycentric(mat3 edges, ivec2 texel) {
    vec3 lambda = edges * ndc(texel);
    return lambda / (lambda.x + lambda.y + lambda.z);
}

// Narrows the texel range [lo, hi] of a row to where a·i + b ≥ 0 (i: the texel's index along the row).
void keep(float a, float b, inout float lo, inout float hi) {
    if (a > 0.0) {
        lo = max(lo, -b / a);
    } else if (a < 0.0) {
        hi = min(hi, -b / a);
    } else if (b < 0.0) {
        hi = -1.0;
    }
}

// Where a crossing lies within this many texels of a texel centre, it is on it (the hardware snaps its
// vertices to 1/256 of a texel): the fill rule decides, and two triangles sharing the edge agree.
const float ON_CENTRE = 1e-4;

// Narrows [lo, hi] to the texels inside edge function λ(i) = a·i + b with Vulkan's top-left rule for texel
// centres on the edge: in where the edge is a left edge (the inside to its right, a > 0) or, parallel to
// the row, a top edge (the inside below it, y down: `down` > 0, λ's step from this row to the next).
void keep_edge(float a, float b, float down, inout float lo, inout float hi) {
    if (a != 0.0) {
        float c = -b / a;
        c = abs(c - round(c)) < ON_CENTRE ? round(c) : c;
        if (a > 0.0) {
            lo = max(lo, c);
        } else {
            hi = min(hi, ceil(c) - 1.0);
        }
        return;
    }
    // Parallel to the row: the row is inside, outside, or on the edge.
    float rows = down != 0.0 ? b / abs(down) : b;
    if (rows < -ON_CENTRE || (abs(rows) < ON_CENTRE && down <= 0.0)) {
        hi = -1.0;
    }
}

// λ of the triangle whose N⁻¹ is `edges` at texel 0 of `row` of the tile at `origin` (h: a texel's width in
// normalized device coordinates); along the row λ steps by h · edges[0] a texel. Set-up (the spans) and
// raster (the depths) both start a row here, so they agree on every texel.
vec3 row_start(mat3 edges, ivec2 origin, int row, float h) {
    vec3 at_origin = (float(origin.x) + 0.5) * h * edges[0] - edges[0] + edges[2];
    return at_origin + ((float(origin.y + row) + 0.5) * h - 1.0) * edges[1];
}

// Set-up of triangle `c` (vertex indices) of view `v` by this invocation, or of none, for the `side`² tile
// at `origin`: its edge functions, depth plane and box, and its span in every row of the tile it reaches.
// Along a row every test is linear in the texel's index i (λ(i) = i·ax + b), so each triangle's texels in
// the row are one span, found from its constraints (inside its three edges by the fill rule, in front of
// the eye, before the near plane, inside the view's clip planes) rather than by testing every texel.
void set_up(uint v, uvec3 c, bool valid, ivec2 origin, uint side) {
    uint i = gl_LocalInvocationID.x;
    s_box[i] = ivec4(1, 0, 0, 0);
    if (!valid) {
        return;
    }
    GpuSensorView view = views[v];
    GpuSurface s = surfaces[floatBitsToUint(vertices[c.x].w)];
    if ((view.flags & VIEW_EMITTERS_ONLY) != 0u && s.ke.w <= 0.0) {
        return;
    }
    vec3 z;
    mat3 world;
    mat3 n = corners_in_view(view, c, z, world);
    vec3 clip[4];  // each clip plane's distance at the corners (1, 1, 1 where all are inside)
    for (uint k = 0u; k < 4u; k++) {
        vec3 d = vec3(dot(view.clip[k], vec4(world[0], 1.0)), dot(view.clip[k], vec4(world[1], 1.0)),
                      dot(view.clip[k], vec4(world[2], 1.0)));
        if (all(lessThan(d, vec3(0.0)))) {
            return;  // wholly outside this plane
        }
        clip[k] = all(greaterThanEqual(d, vec3(0.0))) ? vec3(1.0) : d;
    }
    float det = determinant(n);
    if (det == 0.0) {
        return;  // seen edge-on: no area
    }
    // Texels it may cover: its projection's bounds where every corner is in front of the eye, else (it
    // reaches behind, and its projection is unbounded) the whole layer.
    ivec4 box = ivec4(0, 0, int(push.rd) - 1, int(push.rd) - 1);
    vec3 w = vec3(n[0].z, n[1].z, n[2].z);
    if (all(greaterThan(w, vec3(0.0)))) {
        vec2 p0 = n[0].xy / n[0].z, p1 = n[1].xy / n[1].z, p2 = n[2].xy / n[2].z;
        vec2 lo = (min(p0, min(p1, p2)) + 1.0) * (0.5 * float(push.rd)) - 0.5;
        vec2 hi = (max(p0, max(p1, p2)) + 1.0) * (0.5 * float(push.rd)) - 0.5;
        // (Clamped before the conversion: a corner just in front of the eye projects arbitrarily far.)
        lo = clamp(ceil(lo), vec2(-1.0), vec2(push.rd));
        hi = clamp(floor(hi), vec2(-1.0), vec2(push.rd));
        box = ivec4(max(ivec2(lo), box.xy), min(ivec2(hi), box.zw));
    }
    // The box in the tile's texels.
    box = ivec4(max(box.xy - origin, ivec2(0)), min(box.zw - origin, ivec2(side) - 1));
    if (box.x > box.z || box.y > box.w) {
        return;  // outside this tile
    }
    mat3 edges = inverse(n);
    s_edges[i] = edges;
    s_depth[i] = z;
    s_corners[i] = uvec4(c, v);
    s_box[i] = box;
    float h = 2.0 / float(push.rd);
    vec3 ax = h * edges[0];
    vec3 down = h * edges[1];
    for (int row = box.y; row <= box.w; row++) {
        vec3 b = row_start(edges, origin, row, h);
        float lo = float(box.x), hi = float(box.z);
        for (int e = 0; e < 3; e++) {
            keep_edge(ax[e], b[e], down[e], lo, hi);
        }
        keep(ax.x + ax.y + ax.z, b.x + b.y + b.z, lo, hi);  // in front of the eye
        keep(-dot(z, ax), 1.0 - dot(z, b), lo, hi);  // beyond the near plane (depth ≤ 1)
        for (uint k = 0u; k < 4u; k++) {
            keep(dot(clip[k], ax), dot(clip[k], b), lo, hi);
        }
        ivec2 span = ivec2(clamp(vec2(ceil(lo), floor(hi)), vec2(-1.0), vec2(side))) + 1;  // (finite before int())
        s_span[i * TILE + uint(row)] = uint(span.x) | (uint(span.y) << 16u);
    }
}

// Triangle t's texels in row `row` of the tile: first and last (empty where first > last).
ivec2 span_of(uint t, int row) {
    uint word = s_span[t * TILE + uint(row)];
    return ivec2(word & 0xffffu, word >> 16u) - 1;
}

// Tests this invocation's run of `slots` texels of the `side`² tile at `origin` against the chunk's `count`
// triangles: only a triangle whose span in the run's row(s) (`set_up`) meets the run is read further, and
// each texel of the span then only tests its depth.
void raster(ivec2 origin, uint side, uint slots, uint count) {
    uint first = gl_LocalInvocationID.x * slots;
    if (first >= side * side) {
        return;
    }
    // The run's rows of the tile: it may wrap once onto the next.
    uint last = min(first + slots, side * side) - 1u;
    ivec2 rows = ivec2(first / side, last / side);
    int x0 = int(first % side);
    float h = 2.0 / float(push.rd);
    for (uint t = 0u; t < count; t++) {
        ivec4 box = s_box[t];
        if (box.x > box.z || rows.y < box.y || rows.x > box.w) {
            continue;
        }
        // Only the run's texels in the span (both rows' spans where it wraps).
        int wraps = rows.x == rows.y ? 0 : 1;
        ivec2 span[2];
        for (int r = 0; r <= wraps; r++) {
            span[r] = rows[r] < box.y || rows[r] > box.w ? ivec2(0, -1) : span_of(t, rows[r]);
        }
        int k_first = wraps == 0 ? max(span[0].x - x0, 0) : 0;
        int k_last = wraps == 0 ? min(span[0].y - x0, int(slots) - 1) : int(slots) - 1;
        if (k_first > k_last || (wraps == 1 && span[0].x > span[0].y && span[1].x > span[1].y)) {
            continue;
        }
        mat3 edges = s_edges[t];
        vec3 depths = s_depth[t];
        float step = dot(depths, h * edges[0]);
        vec2 depth_line[2];
        for (int r = 0; r <= wraps; r++) {
            depth_line[r] = vec2(dot(depths, row_start(edges, origin, rows[r], h)), step);
        }
        for (uint k = uint(k_first); int(k) <= k_last; k++) {
            // (No integer division here: CPUs have no vector one, so it would run lane by lane.)
            int x = x0 + int(k), r = 0;
            if (x >= int(side)) {
                x -= int(side);
                r = 1;
            }
            if (first + k > last || x < span[r].x || x > span[r].y) {
                continue;
            }
            float depth = depth_line[r].x + float(x) * depth_line[r].y;
            if (depth <= best_depth[k]) {
                continue;
            }
#ifdef TEXTURES
            uvec3 corners = s_corners[t].xyz;
            vec3 lambda = edges * ndc(ivec2(origin.x + x, origin.y + rows[r]));
            if (cut_out(surfaces[floatBitsToUint(vertices[corners.x].w)], uv_at(corners, lambda / dot(lambda, vec3(1.0))))) {
                continue;
            }
#endif
            best_depth[k] = depth;
            best_corners[k] = s_corners[t];
        }
    }
}

// Sets up and rasterizes triangles `first..first + count` of view `v`: of the soup (`indexed` false: triangle
// t's corners are vertices 3t..3t+2), or of the clusters' index buffer from `first` on, offset by `base`.
void draw(uint v, uint first, uint count, bool indexed, int base, ivec2 origin, uint side, uint slots) {
    for (uint chunk = 0u; chunk < count; chunk += GROUP) {
        uint t = chunk + gl_LocalInvocationID.x;
        uint corner = indexed ? first + 3u * t : 3u * (first + t);
        uvec3 c = indexed ? uvec3(ivec3(indices[corner], indices[corner + 1u], indices[corner + 2u]) + base)
                          : uvec3(corner, corner + 1u, corner + 2u);
        set_up(v, t < count ? c : uvec3(0u), t < count, origin, side);
        barrier();
        raster(origin, side, slots, min(GROUP, count - chunk));
        barrier();
    }
}

// Ck of this invocation's texel `k` of the tile at `origin`, into the maps.
void shade(uint layer, ivec2 origin, uint side, uint slots, uint k) {
    uint local = gl_LocalInvocationID.x * slots + k;
    ivec2 texel = origin + ivec2(local % side, local / side);
    if (local >= side * side || any(greaterThanEqual(texel, ivec2(push.rd)))) {
        return;
    }
    vec4 ck = push.clear;
    if (best_depth[k] > 0.0) {
        uvec4 c = best_corners[k];
        GpuSensorView view = views[c.w];
        vec3 z;
        mat3 world;
        mat3 n = corners_in_view(view, c.xyz, z, world);
        mat3 edges = inverse(n);
        vec3 b = barycentric(edges, texel);
        SensorTexel t;
        t.surface = floatBitsToUint(vertices[c.x].w);
        sensor_sides(surfaces[t.surface], push.sensor, t.ck_front, t.ck_back, t.group);
        t.world = world * b;
        t.eye = view.eye.xyz;
        t.zoom = (view.flags & VIEW_ZOOM) != 0u;
        t.front_facing = determinant(n) < 0.0;
#ifdef TEXTURES
        // uv's steps along x and y as the fragment shader's dFdx, dFdy: coarse, from the texel's 2 × 2 quad
        // (its top-left texel and the next one along each axis), as the rasterizer shades quads.
        ivec2 quad = texel & ~1;
        t.uv = uv_at(c.xyz, b);
        vec2 at_quad = uv_at(c.xyz, barycentric(edges, quad));
        t.dx = uv_at(c.xyz, barycentric(edges, quad + ivec2(1, 0))) - at_quad;
        t.dy = uv_at(c.xyz, barycentric(edges, quad + ivec2(0, 1))) - at_quad;
#endif
        vec4 shaded;
        if (sensor_shade(t, push.sensor, shaded)) {
            ck = shaded;
        }
    }
    imageStore(maps, ivec3(texel, layer), ck);
}

void main() {
    uint layer = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
    if (layer >= push.layer_count) {
        return;  // the whole workgroup: a spilled dispatch's tail
    }
    uint sensor = layer / push.layers;
    uint side = min(push.rd, TILE);
    uint slots = (side * side + GROUP - 1u) / GROUP;  // texels per invocation
    for (uint ty = 0u; ty < push.rd; ty += side) {
        for (uint tx = 0u; tx < push.rd; tx += side) {
            ivec2 origin = ivec2(tx, ty);
            for (uint k = 0u; k < slots; k++) {
                best_depth[k] = 0.0;
            }
            for (uint i = 0u; i < push.per_sensor; i++) {
                uint v = sensor * push.per_sensor + i;
                if (views[v].layer != layer) {
                    continue;
                }
                if (push.culled == 0u) {
                    draw(v, 0u, push.triangles, false, 0, origin, side, slots);
                    continue;
                }
                uint draws = push.count_buffer != 0u ? min(counts[v], push.max_per_view) : push.max_per_view;
                for (uint d = 0u; d < draws; d++) {
                    GpuDrawCommand command = commands[v * push.max_per_view + d];
                    draw(v, command.first_index, command.index_count / 3u, true, command.vertex_offset, origin, side, slots);
                }
            }
            for (uint k = 0u; k < slots; k++) {
                shade(layer, origin, side, slots, k);
            }
        }
    }
}
