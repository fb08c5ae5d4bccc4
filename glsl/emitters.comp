#version 460
// Emitter pass (docs/DESIGN.md §2): each light group's unoccluded irradiance at each sensor of a batch, in
// closed form (polygon.glsl: every emitter triangle clipped to the sensor's domain, Lambert's formula).
// One invocation per (sensor, chunk of emitters); the reduction sums a group's chunks. No barrier here: a
// CPU driver runs a shader with barriers as coroutines, whose frames the clipping's arrays would swell.
#include "types.glsl"
#include "polygon.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Sensors { GpuSensor sensors[]; };
layout(std430, set = 0, binding = 1) readonly buffer Zooms { GpuZoom zooms[]; };  // [sensor][group]
layout(std430, set = 0, binding = 2) readonly buffer Emitters { GpuEmitter emitters[]; };
layout(std430, set = 0, binding = 3) readonly buffer Chunks { GpuEmitterChunk chunks[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Irradiance { vec4 irradiance[]; };  // [sensor][chunk]
layout(push_constant) uniform Push { EmitterPush push; };

void main() {
    // Workgroups beyond the per-dimension limit spill into y.
    uint index = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationIndex;
    uint sensor = index / push.chunks;
    if (sensor >= push.sensors) {
        return;
    }
    GpuEmitterChunk chunk = chunks[index % push.chunks];
    vec3 e = vec3(0.0);
    // A group below the sensor's horizon (no zoom view) sends it nothing: skip its clipping.
    if (zooms[sensor * push.groups + chunk.group].forward.w > 0.0) {
        GpuSensor s = sensors[sensor];
        for (uint k = chunk.first; k < chunk.first + chunk.count; k++) {
            GpuEmitter em = emitters[k];
            e += em.ke.rgb * projected_solid_angle(s, em.v0.xyz, em.v1.xyz, em.v2.xyz);
        }
    }
    irradiance[index] = vec4(e, 0.0);
}
