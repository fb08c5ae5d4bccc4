#version 460
// Reduction (docs/DESIGN.md §3 step 4): one workgroup per sensor reduces its layers to R and writes it
// into the radiance map at the sensor's pixel (w = STATE_SENSED) and into the batch's results, which the
// host reads back: a refinement round reads exactly what it sensed.
//
//   paper's estimator:  R = (1/pi) * sum(Ck * w) over the main layers, w the exact projected solid angle
//                       of each texel (src/sensors/weights.rs);
//   exact estimator:    R = (1/pi) * (sum(Ck_rest * w) + sum_g E_g * V_g), where the main layers hold only
//                       Kd*eps and the background (emitter fronts leave 0), E_g is light group g's
//                       unoccluded irradiance in closed form (polygon.glsl, each triangle clipped to the
//                       sensor's domain), and V_g its visibility: the weighted coverage of g's fronts in
//                       the zoom view drawn with the whole scene over that in the same view drawn with the
//                       emitters alone. Both are rasterised alike, so where nothing occludes V_g is exactly
//                       1 and the quantisation of the sensor map cancels (the ratio estimator of Heitz,
//                       Hill & McGuire 2018).
//
// Layers of one sensor:  | main 0 .. main L-1 | g0 scene | g0 emitters | g1 scene | g1 emitters | ... |
//
// The 8 x 8 threads walk each layer in 8 x 8 blocks (no integer division in the loop: CPU drivers have no
// vector divide), each summing its share; the workgroup then adds the partial sums pairwise in shared
// memory, so rounding grows like log2(64) there, not like the texel count. 64 threads, not 256: a CPU driver
// runs a workgroup's invocations as coroutines that all switch at every barrier, and with 256 the barriers
// cost more than the sums (docs/BENCHMARKS.md); a GPU still has hundreds of sensors' workgroups in flight.
#include "types.glsl"
#include "polygon.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, rgba16f) uniform readonly image2DArray sensor_maps;  // layers, or 1 atlas layer
layout(std430, set = 0, binding = 1) readonly buffer Weights { float weights[]; };  // main [layer][row][col]
layout(std430, set = 0, binding = 2) readonly buffer Pixels { uint pixels[]; };    // pixel of each sensor
layout(std430, set = 0, binding = 3) buffer Radiance { vec4 radiance[]; };         // the radiance map
layout(std430, set = 0, binding = 4) writeonly buffer Results { GpuSensorResult results[]; };
layout(std430, set = 0, binding = 5) readonly buffer Sensors { GpuSensor sensors[]; };  // of the batch
layout(std430, set = 0, binding = 6) readonly buffer Zooms { GpuZoom zooms[]; };  // [sensor][group]
layout(std430, set = 0, binding = 7) readonly buffer Emitters { GpuEmitter emitters[]; };
layout(std430, set = 0, binding = 8) readonly buffer Groups { GpuLightGroup groups[]; };
layout(push_constant) uniform Push { ReducePush push; };

// Per thread: R's rest (3), then per group: E (3), visible and unoccluded coverage (2).
const uint COMPONENTS = 3u + 5u * MAX_GROUPS;
shared float partial[64u * COMPONENTS];

// Where layer `layer` of sensor `sensor` is: an array layer, or a tile of the atlas.
ivec3 map_origin(uint sensor, uint layer) {
    uint slot = sensor * push.layers + layer;
    if (push.atlas_columns != 0u) {
        return ivec3(uvec2(slot % push.atlas_columns, slot / push.atlas_columns) * push.rd, 0);
    }
    return ivec3(0, 0, int(slot));
}

void main() {
    uint sensor = gl_WorkGroupID.x;
    uint lid = gl_LocalInvocationIndex;
    uvec2 thread = gl_LocalInvocationID.xy;
    uint rd = push.rd;

    // The main layers: Ck (the rest, in the exact estimator) weighted by the precomputed texel weights.
    vec3 sum = vec3(0.0);
    for (uint layer = 0u; layer < push.main_layers; layer++) {
        ivec3 origin = map_origin(sensor, layer);
        uint weight_base = layer * rd * rd;
        for (uint y = thread.y; y < rd; y += 8u) {
            uint row = weight_base + y * rd;
            for (uint x = thread.x; x < rd; x += 8u) {
                vec3 ck = imageLoad(sensor_maps, origin + ivec3(x, y, 0)).rgb;
                sum += ck * weights[row + x];
            }
        }
    }
    partial[lid * COMPONENTS + 0u] = sum.r;
    partial[lid * COMPONENTS + 1u] = sum.g;
    partial[lid * COMPONENTS + 2u] = sum.b;

    // Each light group: its exact unoccluded irradiance, and its coverage in the zoom pair.
    GpuSensor s = sensors[sensor];
    for (uint g = 0u; g < MAX_GROUPS; g++) {
        vec3 e = vec3(0.0);
        float visible = 0.0;
        float unoccluded = 0.0;
        GpuZoom zoom;
        if (g < push.groups) {
            zoom = zooms[sensor * push.groups + g];
        }
        if (g < push.groups && zoom.forward.w > 0.0) {
            GpuLightGroup group = groups[g];
            for (uint k = group.first + lid; k < group.first + group.count; k += 64u) {
                GpuEmitter em = emitters[k];
                e += em.ke.rgb * projected_solid_angle(s, em.v0.xyz, em.v1.xyz, em.v2.xyz);
            }
            // Zoom texel weights: cos(theta) d(omega) of each texel, from its direction d through the view
            // plane at distance 1: area * (n . d) / |d|^4, area = (2 tan / rd)^2.
            float tan_half = zoom.right.w;
            float area = (2.0 * tan_half / float(rd)) * (2.0 * tan_half / float(rd));
            float id = float(g + 1u);
            ivec3 with_scene = map_origin(sensor, push.main_layers + 2u * g);
            ivec3 alone = map_origin(sensor, push.main_layers + 2u * g + 1u);
            for (uint y = thread.y; y < rd; y += 8u) {
                float ndc_y = (float(y) + 0.5) * (2.0 / float(rd)) - 1.0;
                for (uint x = thread.x; x < rd; x += 8u) {
                    float ndc_x = (float(x) + 0.5) * (2.0 / float(rd)) - 1.0;
                    vec3 d = zoom.forward.xyz + zoom.right.xyz * (ndc_x * tan_half) - zoom.up.xyz * (ndc_y * tan_half);
                    float len2 = dot(d, d);
                    float w = max(dot(s.n.xyz, d), 0.0) * area / (len2 * len2);
                    if (imageLoad(sensor_maps, with_scene + ivec3(x, y, 0)).a == id) {
                        visible += w;
                    }
                    if (imageLoad(sensor_maps, alone + ivec3(x, y, 0)).a == id) {
                        unoccluded += w;
                    }
                }
            }
        }
        uint base = lid * COMPONENTS + 3u + 5u * g;
        partial[base + 0u] = e.r;
        partial[base + 1u] = e.g;
        partial[base + 2u] = e.b;
        partial[base + 3u] = visible;
        partial[base + 4u] = unoccluded;
    }

    barrier();
    uint used = 3u + 5u * push.groups;  // components in use: the paper's estimator adds only R's three
    for (uint stride = 32u; stride > 0u; stride >>= 1u) {
        if (lid < stride) {
            for (uint c = 0u; c < used; c++) {
                partial[lid * COMPONENTS + c] += partial[(lid + stride) * COMPONENTS + c];
            }
        }
        barrier();
    }
    if (lid == 0u) {
        vec3 r = vec3(partial[0], partial[1], partial[2]);
        GpuSensorResult result;
        for (uint g = 0u; g < MAX_GROUPS; g++) {
            uint base = 3u + 5u * g;
            vec3 e = vec3(partial[base], partial[base + 1u], partial[base + 2u]);
            float visible = partial[base + 3u];
            float unoccluded = partial[base + 4u];
            float v = -1.0;
            if (g < push.groups && max(e.r, max(e.g, e.b)) > 0.0) {
                // No texel of the group in its zoom view (it is edge-on, or smaller than a texel even
                // there): nothing says it is hidden.
                v = unoccluded > 0.0 ? visible / unoccluded : 1.0;
                r += e * v;
            }
            result.visibility[g] = v;
        }
        result.r = vec4(r / PI, STATE_SENSED);
        radiance[pixels[sensor]] = result.r;
        results[sensor] = result;
    }
}
