#version 460
// Atlas strategy: every sensor layer is a tile of one large 2D image. One instance per view; the view's
// clip-space position is squeezed into its tile, and four clip distances (the view frustum's sides) keep
// triangles inside the tile, so no viewport array and no layers are needed:
//
//   atlas NDC x = (x_view_ndc + 1 + 2 * tile_x) / columns - 1      (likewise y with rows)
//
//   +----+----+----+----+
//   | t0 | t1 | t2 | t3 |   tile t = sensor * layers + layer, row-major, rd x rd texels each
//   +----+----+----+----+
//   | t4 | t5 | …  |    |
#include "sensor_common.glsl"

out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[8];
};

void main() {
    GpuSensorView view = views[gl_InstanceIndex];
    float planes[4];
    vec4 clip = sensor_vertex(view, planes);
    for (int k = 0; k < 4; k++) {
        gl_ClipDistance[4 + k] = planes[k];
    }
    gl_ClipDistance[0] = clip.w - clip.x;
    gl_ClipDistance[1] = clip.w + clip.x;
    gl_ClipDistance[2] = clip.w - clip.y;
    gl_ClipDistance[3] = clip.w + clip.y;
    uint tile = view.layer;
    vec2 grid = vec2(push.atlas_columns, push.atlas_rows);
    vec2 cell = vec2(tile % push.atlas_columns, tile / push.atlas_columns);
    vec2 xy = (clip.xy + clip.w * (1.0 + 2.0 * cell)) / grid - clip.w;
    gl_Position = vec4(xy, clip.zw);
}
