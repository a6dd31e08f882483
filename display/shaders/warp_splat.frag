#version 330 core
// The GL re-projection, pass 1: a splatted point's colour and distance. The depth test (LESS,
// on the squared distance) keeps the nearest point and, of equals, the first drawn: the CPU
// warp's rule, since points are drawn in the source's row order.
flat in vec3 colour;
flat in float distance;
flat in float key;
layout(location = 0) out vec4 state;  // rgb, alpha: covered / 255 (1: a source pixel)
layout(location = 1) out float depth;

void main() {
    state = vec4(colour, 1.0 / 255.0);
    depth = distance;
    gl_FragDepth = key;
}
