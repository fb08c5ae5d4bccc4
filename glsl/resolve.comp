#version 460
// The supersampling's resolve (docs/DESIGN.md §11): one invocation per supersampled pixel sums Kd·R
// over its sub-pixel samples, each by the share of the square it stands for (the sky it sees where one
// leaves the scene, which the host put in its albedo), adds the light its square emits (exact, from the
// host) and writes that over the composed image, its alpha the share of the square on a surface
// (coverage). A sample's R is its donor's final
// R (a neighbouring pixel on its surface), or where no pixel around shows its surface, the radiance cache's
// (the host's `own`, less the lights' light); with the exact light, the light groups' light is recomputed at
// the sample: R(s) = R(d) + Σ_g (E_g(s)·V_g(s) − E_g(d)·V_g(d)) / π, E_g in closed form (group_light.glsl),
// V_g chosen by the host (src/supersample/donor.rs). CPU twin: src/supersample/mod.rs resolve_cpu.
#include "types.glsl"
#include "polygon.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Pixels { GpuSupersampledPixel pixels[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { GpuSubSample samples[]; };
// Every pixel's final R (the composition's); donors are read here, never written.
layout(std430, set = 0, binding = 2) readonly buffer Composed { vec4 composed[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Final { vec4 final_image[]; };
// Per supersampled pixel: R averaged over its samples on a surface (the radiance AOV), alpha the coverage.
layout(std430, set = 0, binding = 4) writeonly buffer Resolved { vec4 resolved[]; };
layout(set = 0, binding = 5, rgba32f) uniform readonly image2D positions;
layout(set = 0, binding = 6, rgba32f) uniform readonly image2D normals;
layout(std430, set = 0, binding = 7) readonly buffer Emitters { GpuEmitter emitters[]; };
layout(std430, set = 0, binding = 8) readonly buffer Chunks { GpuEmitterChunk chunks[]; };
layout(std430, set = 0, binding = 9) readonly buffer Groups { GpuLightGroup groups[]; };
layout(push_constant) uniform Push { ResolvePush push; };
#include "group_light.glsl"

// Σ_g E_g·V_g / π at a point on a surface (V_g < 0, not measured: nothing says it is hidden).
vec3 direct(vec3 position, vec3 n, float v[MAX_GROUPS]) {
    GpuSensor s = hemisphere_sensor(position, n, push.bias);
    vec3 sum = vec3(0.0);
    for (uint g = 0u; g < push.groups; g++) {
        sum += group_irradiance(s, g) * (v[g] < 0.0 ? 1.0 : v[g]);
    }
    return sum / PI;
}

void main() {
    // Workgroups beyond the per-dimension limit spill into y.
    uint f = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationIndex;
    if (f >= push.count) {
        return;
    }
    // What the square emits is exact (the host clipped each emitter to it); the samples add what it reflects.
    // Each sample stands for its share of the square (its weight: supersample/coverage.rs).
    vec3 image = vec3(0.0);
    vec3 r = vec3(0.0);
    float hits = 0.0;
    float misses = 0.0;
    for (uint k = 0u; k < push.samples; k++) {
        GpuSubSample s = samples[f * push.samples + k];
        if (s.position.w == 0.0) {
            image += s.weight * s.albedo.rgb;
            misses += s.weight;
            continue;
        }
        vec3 rs = s.own.w == 1.0 ? s.own.rgb : composed[s.donor].rgb;
        if (push.exact != 0u && s.own.w == 1.0) {
            rs += direct(s.position.xyz, s.normal.xyz, s.visibility);
        } else if (push.exact != 0u) {
            ivec2 d = ivec2(s.donor % push.width, s.donor / push.width);
            vec4 donor_position = imageLoad(positions, d);
            vec3 at_donor = donor_position.w == 0.0
                ? vec3(0.0)
                : direct(donor_position.xyz, imageLoad(normals, d).xyz, s.donor_visibility);
            rs = max(rs + direct(s.position.xyz, s.normal.xyz, s.visibility) - at_donor, vec3(0.0));
        }
        image += s.weight * s.albedo.rgb * rs;
        r += s.weight * rs;
        hits += s.weight;
    }
    // The share on a surface, exactly 1 where no sample leaves the scene (the weights' sum is 1 ± rounding).
    float coverage = hits / max(hits + misses, 1e-30);
    final_image[pixels[f].pixel] = vec4(pixels[f].emission.rgb + image, coverage);
    resolved[f] = vec4(hits > 0.0 ? r / hits : vec3(0.0), coverage);
}
