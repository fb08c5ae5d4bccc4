#version 460
// Atlas strategy: every sensor layer is a tile of one large 2D image. One draw per view, its viewport and
// scissor set to the view's tile by the host, so each view is rasterized exactly as into a layer of its
// own (the same clip space, the same window coordinates up to the tile's integer offset):
//
//   +----+----+----+----+
//   | t0 | t1 | t2 | t3 |   tile t = sensor * layers + layer, row-major, rd x rd texels each
//   +----+----+----+----+
//   | t4 | t5 | …  |    |
// variant: TEXTURES (sensor_common.glsl)
#include "sensor_common.glsl"

out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[4];
};

void main() {
    // The instance (firstInstance: the view drawn), or the push constants' view for a per-view list.
    uint view = draw_view();
    float clip[4];
    gl_Position = sensor_vertex(view, clip);
    gl_ClipDistance = clip;
}
