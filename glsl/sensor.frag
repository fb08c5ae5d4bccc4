#version 460
// Sensor maps: each texel stores Ck (paper §III-C): Ke on the front side of an emitter, Kd * epsilon on
// anything else (both prepared by the vertex shader). The clear colour is the background radiance, for
// texels that see no geometry.

layout(location = 0) flat in vec3 in_ck_front;
layout(location = 1) flat in vec3 in_ck_back;
layout(location = 0) out vec4 out_ck;

void main() {
    out_ck = vec4(gl_FrontFacing ? in_ck_front : in_ck_back, 1.0);
}
