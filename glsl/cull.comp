#version 460
// Cluster culling (docs/DESIGN.md §9): for every (cluster, sensor view) of a batch, keep the cluster if it
// can be seen and is the right level of detail, and append a draw of it to that view's indirect commands.
// Dropped: clusters wholly behind the sensor's tangent plane, outside the view's four side planes or one of
// its clip planes, non-emitters in an emitters-only view, and clusters whose level is not the one selected
// by `own error <= tau < parent error` (projected from the sensor; tau is half the view's centre texel).
// CPU twin: passes::cull::keeps.
#include "types.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Clusters { GpuCluster clusters[]; };
layout(std430, set = 0, binding = 1) readonly buffer Views { GpuSensorView views[]; };
layout(std430, set = 0, binding = 2) readonly buffer Sensors { GpuSensor sensors[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Commands { GpuDrawCommand commands[]; };
// counts[v]: the draws of view v; counts[views + v]: their triangles (statistics and tests).
layout(std430, set = 0, binding = 4) buffer Counts { uint counts[]; };
layout(push_constant) uniform Push { CullPush push; };

vec4 row(mat4 m, int i) {
    return vec4(m[0][i], m[1][i], m[2][i], m[3][i]);
}

// Whether the sphere lies wholly on the negative side of the plane (m, d): m·p + d >= 0 is kept.
bool outside(vec4 plane, vec4 sphere) {
    return dot(plane.xyz, sphere.xyz) + plane.w < -sphere.w * length(plane.xyz);
}

float projected(vec4 bounds, float error, vec3 eye) {
    if (error == 0.0) {
        return 0.0;
    }
    return error / max(distance(bounds.xyz, eye) - bounds.w, push.near);
}

void main() {
    uint c = gl_GlobalInvocationID.x;
    uint v = gl_GlobalInvocationID.y;
    if (c >= push.clusters || v >= push.views) {
        return;
    }
    GpuCluster k = clusters[c];
    GpuSensorView view = views[v];
    GpuSensor s = sensors[v / push.per_sensor];
    vec3 eye = s.origin.xyz;
    bool keep = dot(s.n.xyz, k.sphere.xyz - eye) >= -k.sphere.w;
    keep = keep && ((view.flags & VIEW_EMITTERS_ONLY) == 0u || (k.flags & CLUSTER_EMITTER) != 0u);
    for (int i = 0; i < 4; i++) {
        keep = keep && !outside(view.clip[i], k.sphere);
    }
    mat4 m = view.view_proj;
    vec4 w = row(m, 3);
    for (int i = 0; i < 2; i++) {
        keep = keep && !outside(w + row(m, i), k.sphere) && !outside(w - row(m, i), k.sphere);
    }
    float scale = max(length(row(m, 0).xyz), length(row(m, 1).xyz));
    float tau = 1.0 / (float(push.rd) * scale);
    keep = keep && projected(k.own, k.errors.x, eye) <= tau && projected(k.parent, k.errors.y, eye) > tau;
    if (keep) {
        uint slot = atomicAdd(counts[v], 1u);
        atomicAdd(counts[push.views + v], k.index_count / 3u);
        if (slot < push.max_per_view) {
            commands[v * push.max_per_view + slot] = GpuDrawCommand(k.index_count, 1u, k.first_index, 0, v);
        }
    }
}
