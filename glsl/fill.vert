#version 460
// Raw fill rate: one full-screen triangle per instance, into layer gl_InstanceIndex. The benchmark's
// upper bound for drawing sensor maps: no geometry, no vertex work, only clears and fragments.
#extension GL_ARB_shader_viewport_layer_array : require

void main() {
    vec2 p = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    gl_Position = vec4(p * 2.0 - 1.0, 0.5, 1.0);
    gl_Layer = gl_InstanceIndex;
}
