#version 460
// Reduction (docs/DESIGN.md §3 step 5): one workgroup per sensor reduces its layers to R and writes it
// into the radiance map at the sensor's pixel (w = STATE_SENSED) and into the batch's results, which the
// host reads back: a refinement round reads exactly what it sensed. The main layers' share of R (with the
// exact estimator: all but the emitters' closed-form light, so the light surfaces reflect and the
// background) goes into the indirect map too, which the post passes filter apart (docs/DESIGN.md §3).
//
//   paper's estimator:  R = (1/pi) * sum(Ck * w) over the main layers, w the exact projected solid angle
//                       of each texel (src/sensors/weights.rs);
//   exact estimator:    R = (1/pi) * (sum(Ck_rest * w) + sum_g E_g * V_g), where the main layers hold only
//                       Kd*eps and the background (emitter fronts leave 0), E_g is light group g's
//                       unoccluded irradiance in closed form (the emitter pass, emitters.comp, by chunk of
//                       emitters), and V_g its visibility: the weighted coverage of g's fronts in
//                       the zoom view drawn with the whole scene over that in the same view drawn with the
//                       emitters alone. Both are rasterised alike, so where nothing occludes V_g is exactly
//                       1 and the quantisation of the sensor map cancels (the ratio estimator of Heitz,
//                       Hill & McGuire 2018).
//
// A main-layer texel with alpha < 0 saw no geometry under a sky map (the maps were cleared so): its Ck is
// the sky along the texel's direction (`directions`, in the sensor's frame, turned into the world by the
// sensor's t, b, n), averaged over the texel's solid angle (glsl/sky.glsl).
//
// Layers of one sensor:  | main 0 .. main L-1 | g0 scene | g0 emitters | g1 scene | g1 emitters | ... |
//
// The 8 x 8 threads walk each layer in 8 x 8 blocks (no integer division in the loop: CPU drivers have no
// vector divide), each summing its share; the workgroup then adds the partial sums pairwise in shared
// memory, so rounding grows like log2(64) there, not like the texel count. 64 threads, not 256: a CPU driver
// runs a workgroup's invocations as coroutines that all switch at every barrier, and with 256 the barriers
// cost more than the sums (docs/BENCHMARKS.md); a GPU still has hundreds of sensors' workgroups in flight.
//
// Slits (docs/DESIGN.md §3 step 5): a bright surface seen through a gap narrower than a texel (the lit room
// through a door ajar) lands on whole texels or on none, as their centres fall, so one pixel's R is twice the
// truth and its neighbour's half. Where a texel is THIN_BRIGHTNESS times the map's mean and THIN_CONTRAST
// times its darker neighbours along a row or a column (a feature one texel wide), its light is counted; the
// share of the main layers' light such texels hold goes into the results (rest.w), and the renderer senses
// the sensors where it is large again at a finer rd (src/renderer/fine.rs). The second walk that finds them
// runs only where some texel is that bright: most sensors pay one maximum.
#include "types.glsl"
#define SKY_BINDING 11
#include "sky.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, rgba16f) uniform readonly image2DArray sensor_maps;  // layers, or 1 atlas layer
layout(std430, set = 0, binding = 1) readonly buffer Weights { float weights[]; };  // main [layer][row][col]
layout(std430, set = 0, binding = 2) readonly buffer Pixels { uint pixels[]; };    // pixel of each sensor
layout(std430, set = 0, binding = 3) buffer Radiance { vec4 radiance[]; };         // the radiance map
layout(std430, set = 0, binding = 4) writeonly buffer Results { GpuSensorResult results[]; };
layout(std430, set = 0, binding = 5) readonly buffer Sensors { GpuSensor sensors[]; };  // of the batch
layout(std430, set = 0, binding = 6) readonly buffer Zooms { GpuZoom zooms[]; };  // [sensor][group]
layout(std430, set = 0, binding = 7) readonly buffer Irradiance { vec4 irradiance[]; };  // [sensor][chunk]
layout(std430, set = 0, binding = 8) readonly buffer Groups { GpuLightGroup groups[]; };
layout(std430, set = 0, binding = 9) writeonly buffer Indirect { vec4 indirect[]; };  // the main layers' R
// Per main texel ([layer][row][col]): its centre's direction in the sensor frame (t, b, n), and in w the
// solid angle it covers (src/sensors/weights.rs texel_directions).
layout(std430, set = 0, binding = 10) readonly buffer Directions { vec4 directions[]; };
layout(push_constant) uniform Push { ReducePush push; };

shared vec3 partial[64];
// Per thread: the brightest main-layer texel's luminance, then the light of the thin bright texels.
shared float partial_thin[64];
// Per thread, for the light group being measured: its visible and unoccluded coverage.
shared vec2 partial_light[64];
// What the sensor saw of each group, for the results. Kept in shared memory rather than in each thread:
// a CPU driver keeps whatever a thread holds across a barrier in that thread's coroutine frame.
shared float seen[MAX_GROUPS];

const float THIN_BRIGHTNESS = 16.0;
const float THIN_CONTRAST = 4.0;

float luminance(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// Where layer `layer` of sensor `sensor` is: an array layer, or a tile of the atlas.
ivec3 map_origin(uint sensor, uint layer) {
    uint slot = sensor * push.layers + layer;
    if (push.atlas_columns != 0u) {
        return ivec3(uvec2(slot % push.atlas_columns, slot / push.atlas_columns) * push.rd, 0);
    }
    return ivec3(0, 0, int(slot));
}

// The luminance of main-layer texel (x, y) of a layer at `origin`, as the sums count it; a texel off the
// layer or showing the sky counts as `otherwise` (no darker neighbour there).
float neighbour(ivec3 origin, int x, int y, float otherwise) {
    int rd = int(push.rd);
    if (x < 0 || y < 0 || x >= rd || y >= rd) {
        return otherwise;
    }
    vec4 texel = imageLoad(sensor_maps, origin + ivec3(x, y, 0));
    return texel.a < 0.0 ? otherwise : luminance(texel.rgb * (texel.a > 0.0 ? push.emission_scale : 1.0));
}

// The share of the main layers' light `total` (Σ luminance · weight) held by thin bright texels (see the top).
// partial_thin[0] holds the brightest texel's luminance on entry; every thread must call it.
float thin_light(uint main_layers, float total) {
    float bright = THIN_BRIGHTNESS * total / PI;
    if (!(partial_thin[0] > bright) || total <= 0.0) {
        return 0.0;  // nothing that bright: the same answer in every thread
    }
    barrier();  // every thread has read the maximum before it is overwritten
    float light = 0.0;
    uvec2 thread = gl_LocalInvocationID.xy;
    uint rd = push.rd;
    for (uint layer = 0u; layer < main_layers; layer++) {
        ivec3 origin = map_origin(gl_WorkGroupID.x, layer);
        uint weight_base = layer * rd * rd;
        for (uint y = thread.y; y < rd; y += 8u) {
            for (uint x = thread.x; x < rd; x += 8u) {
                float l = neighbour(origin, int(x), int(y), 0.0);
                if (l > bright) {
                    int ix = int(x), iy = int(y);
                    float across = max(neighbour(origin, ix - 1, iy, l), neighbour(origin, ix + 1, iy, l));
                    float along = max(neighbour(origin, ix, iy - 1, l), neighbour(origin, ix, iy + 1, l));
                    light += l > THIN_CONTRAST * min(across, along) ? l * weights[weight_base + y * rd + x] : 0.0;
                }
            }
        }
    }
    uint lid = gl_LocalInvocationIndex;
    partial_thin[lid] = light;
    barrier();
    for (uint stride = 32u; stride > 0u; stride >>= 1u) {
        if (lid < stride) {
            partial_thin[lid] += partial_thin[lid + stride];
        }
        barrier();
    }
    return partial_thin[0] / total;
}

void main() {
    uint sensor = gl_WorkGroupID.x;
    uint lid = gl_LocalInvocationIndex;
    uvec2 thread = gl_LocalInvocationID.xy;
    uint rd = push.rd;

    // The main layers: Ck (the rest, in the exact estimator) weighted by the precomputed texel weights.
    GpuSensor frame = sensors[sensor];
    vec3 sum = vec3(0.0);
    float brightest = 0.0;
    // Main layers drawn with the cache's entries (the transport's rows) hold no light.
    uint main_layers = push.main_entries != 0u ? 0u : push.main_layers;
    for (uint layer = 0u; layer < main_layers; layer++) {
        ivec3 origin = map_origin(sensor, layer);
        uint weight_base = layer * rd * rd;
        for (uint y = thread.y; y < rd; y += 8u) {
            uint row = weight_base + y * rd;
            for (uint x = thread.x; x < rd; x += 8u) {
                vec4 texel = imageLoad(sensor_maps, origin + ivec3(x, y, 0));
                vec3 ck = texel.rgb * (texel.a > 0.0 ? push.emission_scale : 1.0);
                if (texel.a < 0.0) {
                    vec4 d = directions[row + x];
                    ck = sky_radiance(frame.t.xyz * d.x + frame.b.xyz * d.y + frame.n.xyz * d.z, d.w);
                }
                sum += ck * weights[row + x];
                brightest = texel.a >= 0.0 ? max(brightest, luminance(ck)) : brightest;
            }
        }
    }
    partial[lid] = sum;
    partial_thin[lid] = brightest;
    barrier();
    for (uint stride = 32u; stride > 0u; stride >>= 1u) {
        if (lid < stride) {
            partial[lid] += partial[lid + stride];
            partial_thin[lid] = max(partial_thin[lid], partial_thin[lid + stride]);
        }
        barrier();
    }
    vec3 r = partial[0];
    float thin_share = thin_light(main_layers, luminance(r));

    // Each light group: its exact unoccluded irradiance, and its coverage in the zoom pair (exact estimator).
    if (lid < MAX_GROUPS) {
        seen[lid] = -1.0;
    }
    for (uint g = 0u; g < push.groups; g++) {
        GpuZoom zoom = zooms[sensor * push.groups + g];
        if (zoom.forward.w == 0.0) {
            continue;  // below the sensor's horizon, it sends nothing (the same for every thread)
        }
        vec3 n = sensors[sensor].n.xyz;
        // Zoom texel weights: cos(theta) d(omega) of each texel, from its direction d through the view plane
        // at distance 1: area * (n . d) / |d|^4, area = (2 tan_x / rd) (2 tan_y / rd).
        vec2 tan_half = vec2(zoom.right.w, zoom.up.w);
        float area = (2.0 * tan_half.x / float(rd)) * (2.0 * tan_half.y / float(rd));
        float id = float(g + 1u);
        ivec3 with_scene = map_origin(sensor, push.main_layers + 2u * g);
        ivec3 alone = map_origin(sensor, push.main_layers + 2u * g + 1u);
        float visible = 0.0;
        float unoccluded = 0.0;
        for (uint y = thread.y; y < rd; y += 8u) {
            float ndc_y = (float(y) + 0.5) * (2.0 / float(rd)) - 1.0;
            for (uint x = thread.x; x < rd; x += 8u) {
                float ndc_x = (float(x) + 0.5) * (2.0 / float(rd)) - 1.0;
                vec3 d = zoom.forward.xyz + zoom.right.xyz * (ndc_x * tan_half.x) - zoom.up.xyz * (ndc_y * tan_half.y);
                float len2 = dot(d, d);
                float w = max(dot(n, d), 0.0) * area / (len2 * len2);
                visible += imageLoad(sensor_maps, with_scene + ivec3(x, y, 0)).a == id ? w : 0.0;
                unoccluded += imageLoad(sensor_maps, alone + ivec3(x, y, 0)).a == id ? w : 0.0;
            }
        }
        partial_light[lid] = vec2(visible, unoccluded);
        barrier();
        for (uint stride = 32u; stride > 0u; stride >>= 1u) {
            if (lid < stride) {
                partial_light[lid] += partial_light[lid + stride];
            }
            barrier();
        }
        vec2 coverage = partial_light[0];
        barrier();  // every thread has read the totals before the next group overwrites them
        GpuLightGroup group = groups[g];
        vec3 e = vec3(0.0);
        for (uint c = group.first_chunk; c < group.first_chunk + group.chunks; c++) {
            e += irradiance[sensor * push.chunks + c].rgb;
        }
        if (max(e.r, max(e.g, e.b)) > 0.0) {
            // No texel of the group in its zoom view (it is edge-on, or smaller than a texel even there):
            // nothing says it is hidden.
            float v = coverage.y > 0.0 ? coverage.x / coverage.y : 1.0;
            r += e * v;
            if (lid == 0u) {
                seen[g] = v;
            }
        }
    }

    if (lid == 0u) {
        vec4 value = vec4(r / PI, STATE_SENSED);
        radiance[pixels[sensor]] = value;
        indirect[pixels[sensor]] = vec4(partial[0] / PI, STATE_SENSED);
        results[sensor].r = value;
        results[sensor].rest = vec4(partial[0] / PI, thin_share);
        for (uint g = 0u; g < MAX_GROUPS; g++) {
            results[sensor].visibility[g] = seen[g];
        }
    }
}
