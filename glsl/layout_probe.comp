#version 460
// Not a pass: exists so that tests/layout.rs can read the std430 layout of every shared struct out of
// compiled SPIR-V (member offsets, array strides) and compare it with src/gpu_types.rs.
#include "types.glsl"

layout(local_size_x = 1) in;

layout(std430, set = 0, binding = 0) buffer Surfaces { GpuSurface surfaces[]; };
layout(std430, set = 0, binding = 1) buffer GBufferPushes { GBufferPush gbuffer_pushes[]; };
layout(std430, set = 0, binding = 2) buffer SensorViews { GpuSensorView sensor_views[]; };
layout(std430, set = 0, binding = 3) buffer SensorPushes { SensorPush sensor_pushes[]; };
layout(std430, set = 0, binding = 4) buffer ReducePushes { ReducePush reduce_pushes[]; };
layout(std430, set = 0, binding = 5) buffer Quads { GpuQuad quads[]; };
layout(std430, set = 0, binding = 6) buffer ImagePushes { ImagePush image_pushes[]; };
layout(std430, set = 0, binding = 7) buffer Sensors { GpuSensor sensors[]; };
layout(std430, set = 0, binding = 8) buffer Zooms { GpuZoom zooms[]; };
layout(std430, set = 0, binding = 9) buffer Emitters { GpuEmitter emitters[]; };
layout(std430, set = 0, binding = 10) buffer Groups { GpuLightGroup groups[]; };
layout(std430, set = 0, binding = 11) buffer Results { GpuSensorResult results[]; };
layout(std430, set = 0, binding = 12) buffer Chunks { GpuEmitterChunk chunks[]; };
layout(std430, set = 0, binding = 13) buffer EmitterPushes { EmitterPush emitter_pushes[]; };
layout(std430, set = 0, binding = 14) buffer Clusters { GpuCluster clusters[]; };
layout(std430, set = 0, binding = 15) buffer Commands { GpuDrawCommand commands[]; };
layout(std430, set = 0, binding = 16) buffer CullPushes { CullPush cull_pushes[]; };
layout(std430, set = 0, binding = 17) buffer CullNodes { GpuCullNode cull_nodes[]; };
layout(std430, set = 0, binding = 18) buffer CacheGrids { GpuCacheGrid cache_grids[]; };
layout(std430, set = 0, binding = 19) buffer CacheSlots { GpuCacheSlot cache_slots[]; };
layout(std430, set = 0, binding = 20) buffer CacheSplits { GpuCacheSplit cache_splits[]; };
layout(std430, set = 0, binding = 21) buffer ComposePushes { ComposePush compose_pushes[]; };
layout(std430, set = 0, binding = 22) buffer ExactInterpolatePushes { ExactInterpolatePush exact_interpolate_pushes[]; };
layout(std430, set = 0, binding = 23) buffer SubSamples { GpuSubSample sub_samples[]; };
layout(std430, set = 0, binding = 24) buffer ResolvePushes { ResolvePush resolve_pushes[]; };
layout(std430, set = 0, binding = 25) buffer SupersampledPixels { GpuSupersampledPixel supersampled_pixels[]; };
layout(std430, set = 0, binding = 26) buffer Textures { GpuTexture textures[]; };
layout(std430, set = 0, binding = 27) buffer Skies { GpuSky skies[]; };
layout(std430, set = 0, binding = 28) buffer SensorComputePushes { SensorComputePush sensor_compute_pushes[]; };
layout(std430, set = 0, binding = 29) buffer TransportPushes { TransportPush transport_pushes[]; };

void main() {
    // Touch every array so the compiler keeps the types.
    surfaces[1] = surfaces[0];
    gbuffer_pushes[1] = gbuffer_pushes[0];
    sensor_views[1] = sensor_views[0];
    sensor_pushes[1] = sensor_pushes[0];
    reduce_pushes[1] = reduce_pushes[0];
    quads[1] = quads[0];
    image_pushes[1] = image_pushes[0];
    sensors[1] = sensors[0];
    zooms[1] = zooms[0];
    emitters[1] = emitters[0];
    groups[1] = groups[0];
    results[1] = results[0];
    chunks[1] = chunks[0];
    emitter_pushes[1] = emitter_pushes[0];
    clusters[1] = clusters[0];
    commands[1] = commands[0];
    cull_pushes[1] = cull_pushes[0];
    cull_nodes[1] = cull_nodes[0];
    cache_grids[1] = cache_grids[0];
    cache_slots[1] = cache_slots[0];
    cache_splits[1] = cache_splits[0];
    compose_pushes[1] = compose_pushes[0];
    exact_interpolate_pushes[1] = exact_interpolate_pushes[0];
    sub_samples[1] = sub_samples[0];
    resolve_pushes[1] = resolve_pushes[0];
    supersampled_pixels[1] = supersampled_pixels[0];
    textures[1] = textures[0];
    skies[1] = skies[0];
    sensor_compute_pushes[1] = sensor_compute_pushes[0];
    transport_pushes[1] = transport_pushes[0];
}
