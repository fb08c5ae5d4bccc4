#version 460
// Id-constrained Gaussian filter (paper §III-H, docs/DESIGN.md §3 step 6): a Gaussian of radius r (sigma = r/2)
// over the radiance map that only takes samples of the centre pixel's surface id and light mask (which
// points on the lights it sees, sensors::hints; all 0 without hints), renormalising the weights over the
// samples it took. Neither surfaces nor shadows bleed into each other.
#include "types.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) readonly buffer Source { vec4 source[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Target { vec4 target[]; };
layout(set = 0, binding = 2, r32ui) uniform readonly uimage2D surface_ids;
layout(std430, set = 0, binding = 3) readonly buffer LightMasks { uvec2 light_masks[]; };  // 64 bits a pixel
layout(push_constant) uniform Push { ImagePush push; };

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(push.width) || p.y >= int(push.height)) {
        return;
    }
    uint i = uint(p.y) * push.width + uint(p.x);
    uint id = imageLoad(surface_ids, p).r;
    uvec2 mask = light_masks[i];
    int r = int(push.radius);
    if (id == 0u || r == 0) {
        target[i] = source[i];
        return;
    }
    float inv_two_sigma2 = 1.0 / (2.0 * 0.25 * float(r * r));
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (int dy = -r; dy <= r; dy++) {
        for (int dx = -r; dx <= r; dx++) {
            ivec2 q = p + ivec2(dx, dy);
            if (q.x < 0 || q.y < 0 || q.x >= int(push.width) || q.y >= int(push.height)) {
                continue;
            }
            uint j = uint(q.y) * push.width + uint(q.x);
            if (imageLoad(surface_ids, q).r != id || light_masks[j] != mask) {
                continue;
            }
            float k = exp(-float(dx * dx + dy * dy) * inv_two_sigma2);
            sum += k * source[j].rgb;
            weight += k;
        }
    }
    target[i] = vec4(sum / weight, source[i].w);
}
