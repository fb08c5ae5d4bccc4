#version 460
// Composition (docs/DESIGN.md §3 step 7): final = Le + albedo * R.
#include "types.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) readonly buffer Radiance { vec4 radiance[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Final { vec4 final_image[]; };
layout(set = 0, binding = 2, rgba32f) uniform readonly image2D albedo;
layout(set = 0, binding = 3, rgba32f) uniform readonly image2D emission;
layout(push_constant) uniform Push { ImagePush push; };

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(push.width) || p.y >= int(push.height)) {
        return;
    }
    uint i = uint(p.y) * push.width + uint(p.x);
    vec3 le = imageLoad(emission, p).rgb;
    vec3 kd = imageLoad(albedo, p).rgb;
    final_image[i] = vec4(le + kd * radiance[i].rgb, 1.0);
}
