#version 460
// The radiance cache's transport rows (docs/DESIGN.md §10, src/gi/transport.rs): one workgroup per sensor
// copies which cache value each texel of its main layers sees, from maps drawn with CACHE_ENTRIES
// (sensor_shade.glsl: the value's index in three channels of CACHE_ENTRY_BITS, alpha > 0 on any surface),
// into the batch's texel list, [sensor][layer][row][col], TRANSPORT_NONE where the texel sees no surface.
// The host weighs each texel by its projected solid angle (the reduction's weights) and sums them per value:
// a sensor's row of the transport between the cache's entries.
#include "types.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, rgba16f) uniform readonly image2DArray sensor_maps;  // layers, or 1 atlas layer
layout(std430, set = 0, binding = 1) writeonly buffer Texels { uint texels[]; };
layout(push_constant) uniform Push { TransportPush push; };

void main() {
    uint sensor = gl_WorkGroupID.x;
    uvec2 thread = gl_LocalInvocationID.xy;
    uint rd = push.rd;
    uint mask = (1u << CACHE_ENTRY_BITS) - 1u;
    for (uint layer = 0u; layer < push.main_layers; layer++) {
        // Where the layer is: an array layer, or a tile of the atlas (reduce.comp's map_origin).
        uint slot = sensor * push.layers + layer;
        ivec3 origin = push.atlas_columns != 0u
            ? ivec3(uvec2(slot % push.atlas_columns, slot / push.atlas_columns) * rd, 0)
            : ivec3(0, 0, int(slot));
        uint base = (sensor * push.main_layers + layer) * rd * rd;
        for (uint y = thread.y; y < rd; y += 8u) {
            for (uint x = thread.x; x < rd; x += 8u) {
                vec4 texel = imageLoad(sensor_maps, origin + ivec3(x, y, 0));
                uvec3 digits = uvec3(texel.rgb) & mask;
                uint value = digits.x | (digits.y << CACHE_ENTRY_BITS) | (digits.z << (2u * CACHE_ENTRY_BITS));
                texels[base + y * rd + x] = texel.a > 0.0 ? value : TRANSPORT_NONE;
            }
        }
    }
}
