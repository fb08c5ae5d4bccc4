#version 460
// Raw fill rate: a constant colour, the cheapest fragment there is.

layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(0.25, 0.5, 0.75, 1.0);
}
