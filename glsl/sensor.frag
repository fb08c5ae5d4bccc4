#version 460
// Sensor maps: each texel stores Ck (paper §III-C) as the vertex shader prepared it for the side seen, and
// in alpha the light group + 1 of an emitter's front (0 otherwise), from which the reduction measures each
// group's visibility. The clear colour is the background radiance, for texels that see no geometry.

layout(location = 0) flat in vec3 in_ck_front;
layout(location = 1) flat in vec3 in_ck_back;
layout(location = 2) flat in float in_group;
layout(location = 0) out vec4 out_ck;

void main() {
    out_ck = gl_FrontFacing ? vec4(in_ck_front, in_group) : vec4(in_ck_back, 0.0);
}
