#version 460
// Cluster culling (docs/DESIGN.md §9): for every sensor view of a batch, walk the clusters' bounding tree
// (clusters::tree) down from its root, one depth per dispatch, and append a draw of each cluster the view
// keeps to that view's indirect commands (and the command to the triangle pass's list).
//
// One invocation per (node, view) pair of depth `step`: step 0 takes the root for every view; later steps
// take the pairs the step before queued. An inner node queues each child the view may keep something of;
// a leaf tests its clusters. Dropped, for a cluster's sphere or a node's (which holds its clusters'): wholly
// behind the sensor's tangent plane (for a cluster also its slab, clusters::reach, and its box), outside the
// view's four side planes or one of its clip planes (for a cluster also by its box), not an emitter in an
// emitters-only view; and clusters whose level is not the one selected by `own error <= tau < parent error`
// (projected from the sensor; tau is half the view's centre texel), nodes where no cluster below can be
// (their largest parent error projects to at most tau, or their smallest own error to more). CPU twins:
// passes::cull::keeps (what the walk keeps), clusters::TreeNode::may_select.
#include "types.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Clusters { GpuCluster clusters[]; };
layout(std430, set = 0, binding = 1) readonly buffer Views { GpuSensorView views[]; };
layout(std430, set = 0, binding = 2) readonly buffer Sensors { GpuSensor sensors[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Commands { GpuDrawCommand commands[]; };
// counts[v]: the draws of view v; counts[views + v]: their triangles (statistics and tests); further
// blocks of `views` for the triangle pass (passes::cull).
layout(std430, set = 0, binding = 4) buffer Counts { uint counts[]; };
layout(std430, set = 0, binding = 5) readonly buffer Nodes { GpuCullNode nodes[]; };
// The clusters of the leaves, leaf by leaf.
layout(std430, set = 0, binding = 6) readonly buffer Items { uint items[]; };
// (node, view) pairs, depth by depth.
layout(std430, set = 0, binding = 7) buffer Queue { uvec2 queue[]; };
// Per depth: (pairs queued, workgroups to take them, 1, 1); yzw are a VkDispatchIndirectCommand.
layout(std430, set = 0, binding = 8) buffer Walk { uvec4 walk[]; };
// Every command written, for the triangle pass where it runs (push.region > 0; cull_triangles.comp):
// (commands, workgroups, 1, 1), then each command's index.
layout(std430, set = 0, binding = 9) buffer Kept { uvec4 kept_dispatch; uint kept[]; };
// Each view's command over its region of the triangle pass's pool: started here, filled by that pass.
layout(std430, set = 0, binding = 10) writeonly buffer Regions { GpuDrawCommand regions[]; };
layout(push_constant) uniform Push { CullPush push; };

const uint GROUP = 64u;
// The fewest workgroups a dispatch may count (maxComputeWorkGroupCount[0]): the triangle pass loops over
// the rest.
const uint MAX_WORKGROUPS = 65535u;
// cull_triangles.comp's workgroup: a command per invocation.
const uint TRIANGLE_GROUP = 64u;

vec4 row(mat4 m, int i) {
    return vec4(m[0][i], m[1][i], m[2][i], m[3][i]);
}

// Whether the sphere lies wholly on the negative side of the plane (m, d): m·p + d >= 0 is kept.
bool outside(vec4 plane, vec4 sphere) {
    return dot(plane.xyz, sphere.xyz) + plane.w < -sphere.w * length(plane.xyz);
}

// Whether the view may see anything within `sphere` (of something flagged `flags`).
bool sees(GpuSensorView view, GpuSensor s, vec4 sphere, uint flags) {
    bool keep = dot(s.n.xyz, sphere.xyz - s.origin.xyz) >= -sphere.w;
    keep = keep && ((view.flags & VIEW_EMITTERS_ONLY) == 0u || (flags & CLUSTER_EMITTER) != 0u);
    for (int i = 0; i < 4; i++) {
        keep = keep && !outside(view.clip[i], sphere);
    }
    mat4 m = view.view_proj;
    vec4 w = row(m, 3);
    for (int i = 0; i < 2; i++) {
        keep = keep && !outside(w + row(m, i), sphere) && !outside(w - row(m, i), sphere);
    }
    return keep;
}

// Whether the view may see anything within the box [lo, hi] (passes::cull::box_sees): it reaches above the
// sensor's tangent plane, and inside every side and clip plane (each plane's farthest corner of the box).
bool inside(vec4 plane, vec3 lo, vec3 hi) {
    return dot(plane.xyz, mix(lo, hi, greaterThanEqual(plane.xyz, vec3(0.0)))) + plane.w >= 0.0;
}

bool box_sees(GpuSensorView view, GpuSensor s, vec3 lo, vec3 hi) {
    bool keep = inside(vec4(s.n.xyz, -dot(s.n.xyz, s.origin.xyz)), lo, hi);
    for (int i = 0; i < 4; i++) {
        keep = keep && inside(view.clip[i], lo, hi);
    }
    mat4 m = view.view_proj;
    vec4 w = row(m, 3);
    for (int i = 0; i < 2; i++) {
        keep = keep && inside(w + row(m, i), lo, hi) && inside(w - row(m, i), lo, hi);
    }
    return keep;
}

// The largest dot(dir, p) over a cluster's points, at most (clusters::reach): `dir` a unit vector.
float reach(vec4 sphere, vec4 slab, vec3 dir) {
    float along = dot(dir, slab.xyz);
    float across = sqrt(max(1.0 - along * along, 0.0));
    return dot(dir, sphere.xyz) + abs(along) * slab.w + across * sphere.w;
}

// The distance from p to the nearest point of the box [lo, hi] (0 inside), and to its farthest point.
float nearest(vec3 lo, vec3 hi, vec3 p) {
    return length(max(max(lo - p, p - hi), vec3(0.0)));
}

float farthest(vec3 lo, vec3 hi, vec3 p) {
    return length(max(abs(p - lo), abs(p - hi)));
}

// The error of a bound (its box, error in min.w) as an angle from the eye (clusters::projected_error).
float projected(vec4 lo, vec4 hi, vec3 eye) {
    if (lo.w == 0.0) {
        return 0.0;
    }
    return lo.w / max(nearest(lo.xyz, hi.xyz, eye), push.near);
}

void main() {
    uint node;
    uint v;
    if (push.step == 0u) {
        v = gl_GlobalInvocationID.x;
        node = push.root;
        if (v >= push.views) {
            return;
        }
        if (push.region > 0u) {
            regions[v] = GpuDrawCommand(0u, 1u, v * push.region, 0, v);
        }
    } else {
        uint i = gl_GlobalInvocationID.x;
        if (i >= min(walk[push.step].x, push.in_capacity)) {
            return;
        }
        uvec2 pair = queue[push.in_base + i];
        node = pair.x;
        v = pair.y;
    }
    GpuSensorView view = views[v];
    GpuSensor s = sensors[v / push.per_sensor];
    vec3 eye = s.origin.xyz;
    mat4 m = view.view_proj;
    float tau = 1.0 / (float(push.rd) * max(length(row(m, 0).xyz), length(row(m, 1).xyz)));
    GpuCullNode here = nodes[node];
    if ((here.flags & NODE_LEAF) != 0u) {
        for (uint j = 0u; j < here.count; j++) {
            GpuCluster k = clusters[items[here.first + j]];
            bool keep = sees(view, s, k.sphere, k.flags) && box_sees(view, s, k.box_min.xyz, k.box_max.xyz)
                && reach(k.sphere, k.slab, s.n.xyz) >= dot(s.n.xyz, eye)
                && projected(k.own_min, k.own_max, eye) <= tau && projected(k.parent_min, k.parent_max, eye) > tau;
            if (keep) {
                uint slot = atomicAdd(counts[v], 1u);
                atomicAdd(counts[push.views + v], k.index_count / 3u);
                if (slot < push.max_per_view) {
                    uint command = v * push.max_per_view + slot;
                    commands[command] = GpuDrawCommand(k.index_count, 1u, k.first_index, 0, v);
                    if (push.region > 0u) {
                        uint at = atomicAdd(kept_dispatch.x, 1u);
                        // passes::cull::back_hidden: the eye outside the box of a part that hides its back faces
                        // (closed, or capped), by more than the near plane.
                        bool closed = (k.flags & CLUSTER_CLOSED) != 0u;
                        vec3 margin = vec3(push.near);
                        bool outside = any(lessThan(eye, k.part_min.xyz - margin))
                            || any(greaterThan(eye, k.part_max.xyz + margin));
                        kept[at] = command | (closed && outside ? KEPT_BACK_HIDDEN : 0u);
                        atomicMax(kept_dispatch.y, min(at / TRIANGLE_GROUP + 1u, MAX_WORKGROUPS));
                    }
                }
            }
        }
        return;
    }
    for (uint j = 0u; j < here.count; j++) {
        uint child = here.first + j;
        GpuCullNode c = nodes[child];
        // TreeNode::may_select: the largest parent error too coarse somewhere, the smallest own error fine.
        bool keep = sees(view, s, c.sphere, c.flags)
            && projected(c.parent_min, c.parent_max, eye) > tau
            && c.own_min.w / max(farthest(c.own_min.xyz, c.own_max.xyz, eye), push.near) <= tau;
        if (keep) {
            uint slot = atomicAdd(walk[push.step + 1u].x, 1u);
            if (slot < push.out_capacity) {
                queue[push.out_base + slot] = uvec2(child, v);
                atomicMax(walk[push.step + 1u].y, slot / GROUP + 1u);
            }
        }
    }
}
