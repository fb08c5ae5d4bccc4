// A light group's unoccluded irradiance Σ Ke·(projected solid angle) at a sensor over the hemisphere: the
// emitter pass's formula, for the passes that compute the exact light per pixel or per sub-pixel sample.
// CPU twin: src/light/groups.rs Lights::unoccluded. The includer declares the buffers `emitters` (GpuEmitter),
// `chunks` (GpuEmitterChunk) and `groups` (GpuLightGroup), and includes polygon.glsl.

// A sensor on the surface at `position` facing `n`, lifted by `bias`; the hemisphere needs no tangents.
GpuSensor hemisphere_sensor(vec3 position, vec3 n, float bias) {
    GpuSensor s;
    s.origin = vec4(position + n * bias, 0.0);
    s.t = vec4(0.0);
    s.b = vec4(0.0);
    s.n = vec4(n, 0.0);
    return s;
}

vec3 group_irradiance(GpuSensor s, uint g) {
    vec3 e = vec3(0.0);
    GpuLightGroup group = groups[g];
    for (uint c = group.first_chunk; c < group.first_chunk + group.chunks; c++) {
        GpuEmitterChunk chunk = chunks[c];
        for (uint k = chunk.first; k < chunk.first + chunk.count; k++) {
            GpuEmitter em = emitters[k];
            e += em.ke.rgb * projected_solid_angle(s, em.v0.xyz, em.v1.xyz, em.v2.xyz);
        }
    }
    return e;
}
