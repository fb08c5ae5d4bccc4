#version 460
// Reduction (DESIGN.md §3 step 4): one workgroup per sensor computes R = (1/pi) * sum(Ck * w) over the
// sensor's layers, with w the exact projected solid angle of each texel (src/sensors/weights.rs), and
// writes it into the radiance map at the sensor's pixel with w = STATE_SENSED.
//
// Each thread first sums a strided share of the texels (a few hundred at rd 256), then the workgroup adds
// the partial sums pairwise in shared memory: rounding error grows like log2(256) there, not like the
// texel count.
#include "types.glsl"

layout(local_size_x = 256) in;

layout(set = 0, binding = 0, rgba16f) uniform readonly image2DArray sensor_maps;
layout(std430, set = 0, binding = 1) readonly buffer Weights { float weights[]; };  // [layer][row][col]
layout(std430, set = 0, binding = 2) readonly buffer Pixels { uint pixels[]; };    // pixel of each sensor
layout(std430, set = 0, binding = 3) buffer Radiance { vec4 radiance[]; };         // the radiance map
layout(push_constant) uniform Push { ReducePush push; };

shared vec3 partial[256];

void main() {
    uint sensor = gl_WorkGroupID.x;
    uint lid = gl_LocalInvocationID.x;
    uint texels_per_layer = push.rd * push.rd;
    uint texels = texels_per_layer * push.layers;
    int first_layer = int(sensor * push.layers);

    vec3 sum = vec3(0.0);
    for (uint t = lid; t < texels; t += 256u) {
        uint layer = t / texels_per_layer;
        uint texel = t - layer * texels_per_layer;
        ivec3 at = ivec3(int(texel % push.rd), int(texel / push.rd), first_layer + int(layer));
        sum += imageLoad(sensor_maps, at).rgb * weights[t];
    }
    partial[lid] = sum;
    barrier();
    for (uint stride = 128u; stride > 0u; stride >>= 1u) {
        if (lid < stride) {
            partial[lid] += partial[lid + stride];
        }
        barrier();
    }
    if (lid == 0u) {
        radiance[pixels[push.first_sensor + sensor]] = vec4(partial[0] / PI, STATE_SENSED);
    }
}
