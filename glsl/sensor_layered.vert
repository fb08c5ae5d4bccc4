#version 460
// Layered strategy: one instance per sensor view; the vertex shader routes the triangle to the view's
// layer of the 2D-array framebuffer with gl_Layer (Vulkan 1.2 shaderOutputLayer).
#extension GL_ARB_shader_viewport_layer_array : require
// variant: TEXTURES (sensor_common.glsl)
#include "sensor_common.glsl"

out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[4];
};

void main() {
    // The instance (firstInstance: the first view drawn), or the push constants' view for a per-view list.
    uint view = draw_view();
    float clip[4];
    gl_Position = sensor_vertex(view, clip);
    gl_ClipDistance = clip;
    gl_Layer = int(views[view].layer - push.layer_base);
}
