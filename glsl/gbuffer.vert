#version 460
// G-buffer pass (paper §III-F): the scene from the camera, at the output resolution.
#include "types.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in uint in_surface;

// One shading normal per vertex of the soup (on its triangle's front side; the front normal itself on a flat
// mesh), pulled by vertex index and interpolated across the triangle.
layout(std430, set = 0, binding = 1) readonly buffer Normals { vec4 normals[]; };
// The same for texture coordinates ((0, 0) on a mesh without textures).
layout(std430, set = 0, binding = 2) readonly buffer Uvs { vec2 uvs[]; };
layout(push_constant) uniform Push { GBufferPush push; };

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) flat out uint out_surface;
layout(location = 3) out vec2 out_uv;

void main() {
    out_position = in_position;
    out_normal = normals[gl_VertexIndex].xyz;
    out_surface = in_surface;
    out_uv = uvs[gl_VertexIndex];
    gl_Position = push.view_proj * vec4(in_position, 1.0);
}
