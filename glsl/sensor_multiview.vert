#version 460
// Multiview strategy (VK_KHR_multiview): the render pass's view mask runs this shader once per view;
// gl_ViewIndex picks the sensor view, and view i always lands in layer i of the framebuffer's attachment.
#extension GL_EXT_multiview : require
// variant: TEXTURES (sensor_common.glsl)
#include "sensor_common.glsl"

out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[4];
};

void main() {
    uint view = push.first_view + uint(gl_ViewIndex);
    float clip[4];
    gl_Position = sensor_vertex(view, clip);
    gl_ClipDistance = clip;
}
