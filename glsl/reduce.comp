#version 460
// Reduction (docs/DESIGN.md §3 step 4): one workgroup per sensor computes R = (1/pi) * sum(Ck * w) over the
// sensor's layers, with w the exact projected solid angle of each texel (src/sensors/weights.rs), and
// writes it into the radiance map at the sensor's pixel with w = STATE_SENSED, and into the batch's
// results (one vec4 per sensor, host-visible) so that the refinement reads back only what it sensed.
//
// The 8 x 8 threads walk each layer in 8 x 8 blocks (no integer division in the loop: CPU drivers
// have no vector divide), each summing its share (3072 texels of a hemicube at rd 256); the workgroup then
// adds the partial sums pairwise in shared memory, so rounding grows like log2(64) there, not like the
// texel count. 64 threads, not 256: a CPU driver runs a workgroup's invocations as coroutines that all
// switch at every barrier, and with 256 the barriers cost more than the sums (docs/BENCHMARKS.md); a GPU
// still has hundreds of sensors' workgroups in flight.
#include "types.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, rgba16f) uniform readonly image2DArray sensor_maps;  // layers, or 1 atlas layer
layout(std430, set = 0, binding = 1) readonly buffer Weights { float weights[]; };  // [layer][row][col]
layout(std430, set = 0, binding = 2) readonly buffer Pixels { uint pixels[]; };    // pixel of each sensor
layout(std430, set = 0, binding = 3) buffer Radiance { vec4 radiance[]; };         // the radiance map
layout(std430, set = 0, binding = 4) writeonly buffer Results { vec4 results[]; }; // R of each sensor
layout(push_constant) uniform Push { ReducePush push; };

shared vec3 partial[64];

void main() {
    uint sensor = gl_WorkGroupID.x;
    uint lid = gl_LocalInvocationIndex;
    uvec2 thread = gl_LocalInvocationID.xy;
    uint rd = push.rd;

    vec3 sum = vec3(0.0);
    for (uint layer = 0u; layer < push.layers; layer++) {
        // Where this layer's map is: an array layer, or a tile of the atlas.
        uint slot = sensor * push.layers + layer;
        ivec2 origin = ivec2(0);
        int array_layer = int(slot);
        if (push.atlas_columns != 0u) {
            origin = ivec2(uvec2(slot % push.atlas_columns, slot / push.atlas_columns) * rd);
            array_layer = 0;
        }
        uint weight_base = layer * rd * rd;
        for (uint y = thread.y; y < rd; y += 8u) {
            uint row = weight_base + y * rd;
            for (uint x = thread.x; x < rd; x += 8u) {
                vec3 ck = imageLoad(sensor_maps, ivec3(origin + ivec2(x, y), array_layer)).rgb;
                sum += ck * weights[row + x];
            }
        }
    }
    partial[lid] = sum;
    barrier();
    for (uint stride = 32u; stride > 0u; stride >>= 1u) {
        if (lid < stride) {
            partial[lid] += partial[lid + stride];
        }
        barrier();
    }
    if (lid == 0u) {
        vec4 r = vec4(partial[0] / PI, STATE_SENSED);
        radiance[pixels[sensor]] = r;
        results[sensor] = r;
    }
}
