#version 460
// Composition (docs/DESIGN.md §3 step 7): final = Le + albedo * R, where R is the filtered radiance map and,
// where the indirect part is filtered apart (push.radius != 0), R = R_f - I_f + I_i (R and its indirect part
// at R's filter radius, the indirect part at its own). R is written too: the radiance AOV. A pixel where no
// surface is seen shows the background radiance (or under a sky map its own, from the host), with alpha 0 (coverage: 1 on surfaces) so that the image
// can still be composited over another background.
#include "types.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) readonly buffer Radiance { vec4 radiance[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Final { vec4 final_image[]; };
layout(set = 0, binding = 2, rgba32f) uniform readonly image2D albedo;
layout(set = 0, binding = 3, rgba32f) uniform readonly image2D emission;
layout(std430, set = 0, binding = 4) readonly buffer IndirectAtR { vec4 indirect_at_r[]; };
layout(std430, set = 0, binding = 5) readonly buffer IndirectOwn { vec4 indirect_own[]; };
layout(std430, set = 0, binding = 6) writeonly buffer Composed { vec4 composed[]; };
layout(set = 0, binding = 7, r32ui) uniform readonly uimage2D surface_ids;
// Under a sky map (push.sky): the sky each pixel shows where no surface is (src/scene/sky.rs SkyMap::pixels).
layout(std430, set = 0, binding = 8) readonly buffer SkyPixels { vec4 sky_pixels[]; };
layout(push_constant) uniform Push { ComposePush push; };

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(push.width) || p.y >= int(push.height)) {
        return;
    }
    uint i = uint(p.y) * push.width + uint(p.x);
    if (imageLoad(surface_ids, p).r == NO_SURFACE) {
        composed[i] = vec4(0.0);
        final_image[i] = vec4(push.sky != 0u ? sky_pixels[i].rgb : push.background.rgb, 0.0);
        return;
    }
    vec3 le = imageLoad(emission, p).rgb;
    vec3 kd = imageLoad(albedo, p).rgb;
    vec3 r = radiance[i].rgb;
    if (push.apart != 0u) {
        // Rounding must not turn a black pixel negative.
        r = max(r - indirect_at_r[i].rgb + indirect_own[i].rgb, vec3(0.0));
    }
    composed[i] = vec4(r, radiance[i].w);
    final_image[i] = vec4(le + kd * r, 1.0);
}
