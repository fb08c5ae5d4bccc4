#version 460
// Interpolation (paper §III-G, docs/DESIGN.md §3 step 5): one workgroup per quad fills the quad's own pixels by
// bilinear interpolation of its four sensed corners. Sensed pixels keep their value.
#include "types.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

layout(std430, set = 0, binding = 0) readonly buffer Quads { GpuQuad quads[]; };
layout(std430, set = 0, binding = 1) buffer Radiance { vec4 radiance[]; };
layout(push_constant) uniform Push { ImagePush push; };

void main() {
    uint index = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (index >= push.count) {
        return;
    }
    GpuQuad q = quads[index];
    vec3 c00 = radiance[q.y0 * push.width + q.x0].rgb;
    vec3 c10 = radiance[q.y0 * push.width + q.x1].rgb;
    vec3 c01 = radiance[q.y1 * push.width + q.x0].rgb;
    vec3 c11 = radiance[q.y1 * push.width + q.x1].rgb;
    float w = float(max(q.x1 - q.x0, 1u));
    float h = float(max(q.y1 - q.y0, 1u));
    for (uint y = q.y0 + gl_LocalInvocationID.y; y <= q.own_y1; y += 16u) {
        for (uint x = q.x0 + gl_LocalInvocationID.x; x <= q.own_x1; x += 16u) {
            uint i = y * push.width + x;
            if (radiance[i].w == STATE_SENSED) {
                continue;
            }
            float fx = float(x - q.x0) / w;
            float fy = float(y - q.y0) / h;
            vec3 r = mix(mix(c00, c10, fx), mix(c01, c11, fx), fy);
            radiance[i] = vec4(r, STATE_INTERPOLATED);
        }
    }
}
