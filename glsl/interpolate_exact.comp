#version 460
// Interpolation that keeps the exact light exact (docs/DESIGN.md §3 step 5): one workgroup per quad fills the
// quad's own pixels that were not sensed. The exact estimator's R is Σ_g E_g·V_g + the rest (the main layers:
// the indirect light, Kd·ε, the background), and only E_g, each light group's unoccluded irradiance, is known
// in closed form everywhere. So at each pixel E_g is computed here exactly (polygon.glsl, the emitter pass's
// formula, at the sensor a pixel there would have: lifted by `bias` along the G-buffer's normal, over the
// hemisphere), and only what the sensors measured is interpolated bilinearly from the four corners: each
// group's visibility V_g and the rest. Where nothing occludes, the pixel is what a sensor there would find,
// whatever the curvature of R. Used with the hemicube (rotation-free domain) and the exact estimator only.
// One invocation per pixel to fill (the host lists them with their quad): a pixel costs a loop over the
// emitters here, and most quads are a few pixels, so a workgroup per quad would leave most lanes idle.
#include "types.glsl"
#include "polygon.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Quads { GpuQuad quads[]; };
// (pixel, quad) of each pixel to fill: the quads' own pixels that were not sensed.
layout(std430, set = 0, binding = 9) readonly buffer Fills { uvec2 fills[]; };
layout(std430, set = 0, binding = 1) buffer Radiance { vec4 radiance[]; };
// The sensed corners' rest (R's main layers; interpolated apart by interpolate.comp, which never writes a
// sensed pixel, so its corners are stable while this runs).
layout(std430, set = 0, binding = 2) readonly buffer Indirect { vec4 indirect[]; };
// [quad][corner 00, 10, 01, 11][group]: V_g measured at each corner, < 0 where the corner did not measure g.
layout(std430, set = 0, binding = 3) readonly buffer CornerVisibility { float corner_visibility[]; };
layout(set = 0, binding = 4, rgba32f) uniform readonly image2D positions;
layout(set = 0, binding = 5, rgba32f) uniform readonly image2D normals;
layout(std430, set = 0, binding = 6) readonly buffer Emitters { GpuEmitter emitters[]; };
layout(std430, set = 0, binding = 7) readonly buffer Chunks { GpuEmitterChunk chunks[]; };
layout(std430, set = 0, binding = 8) readonly buffer Groups { GpuLightGroup groups[]; };
layout(push_constant) uniform Push { ExactInterpolatePush push; };  // count: pixels to fill
#include "group_light.glsl"

void main() {
    // Workgroups beyond the per-dimension limit spill into y.
    uint f = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationIndex;
    if (f >= push.count) {
        return;
    }
    uint i = fills[f].x;
    uint index = fills[f].y;
    GpuQuad q = quads[index];
    uint corner[4] = uint[4](q.y0 * push.width + q.x0, q.y0 * push.width + q.x1, q.y1 * push.width + q.x0,
                             q.y1 * push.width + q.x1);
    uint x = i % push.width;
    uint y = i / push.width;
    float fx = float(x - q.x0) / float(max(q.x1 - q.x0, 1u));
    float fy = float(y - q.y0) / float(max(q.y1 - q.y0, 1u));
    float weight[4] = float[4]((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy);
    vec3 rest = vec3(0.0);
    vec3 bilinear = vec3(0.0);
    for (uint c = 0u; c < 4u; c++) {
        rest += weight[c] * indirect[corner[c]].rgb;
        bilinear += weight[c] * radiance[corner[c]].rgb;
    }
    vec4 position = imageLoad(positions, ivec2(x, y));
    vec3 n = imageLoad(normals, ivec2(x, y)).xyz;
    if (position.w == 0.0) {
        radiance[i] = vec4(bilinear, STATE_INTERPOLATED);  // no surface: nothing to compute
        return;
    }
    GpuSensor s = hemisphere_sensor(position.xyz, n, push.bias);
    vec3 direct = vec3(0.0);
    for (uint g = 0u; g < push.groups; g++) {
        vec3 e = group_irradiance(s, g);
        if (max(e.r, max(e.g, e.b)) <= 0.0) {
            continue;
        }
        // V_g over the corners that measured it (on an edge whose two corners did not, the mean of the
        // others); none did (g below all their horizons): nothing says it is hidden, as in the reduction.
        vec2 weighted = vec2(0.0);  // (Σ w·V, Σ w) over the corners that measured g
        vec2 plain = vec2(0.0);     // (Σ V, count)
        for (uint c = 0u; c < 4u; c++) {
            float vc = corner_visibility[(index * 4u + c) * MAX_GROUPS + g];
            if (vc >= 0.0) {
                weighted += vec2(weight[c] * vc, weight[c]);
                plain += vec2(vc, 1.0);
            }
        }
        float v = weighted.y > 0.0 ? weighted.x / weighted.y : plain.y > 0.0 ? plain.x / plain.y : 1.0;
        direct += e * v;
    }
    radiance[i] = vec4(rest + direct / PI, STATE_INTERPOLATED);
}
