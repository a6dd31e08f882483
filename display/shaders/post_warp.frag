#version 330 core
// A calibrated screen's post-warp (issue 30; PostWarpStage, whose apply() is the CPU reference):
// each pixel takes its pane's (eye's) flat image at its target, bilinearly between pixel centres,
// clamped at the edges, black off the image. The bilinear weights are computed here in float
// (not by the sampler's fixed-point filter) so that the GPU agrees with the CPU to a code.
uniform sampler2D shown;    // a copy of the screen's back buffer (GL rows: bottom first)
uniform sampler2D targets;  // RG32F, per screen pixel (row 0 the top row): x, y in screen pixels from the top left
uniform ivec2 size;
uniform int split;          // a side-by-side screen's second pane starts at this column (else size.x)
out vec4 colour;

vec3 texel(int x, int y) { return texelFetch(shown, ivec2(x, size.y - 1 - y), 0).rgb; }

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    // The pane (one eye's image) this pixel is in: its first column and width; targets are in its pixels.
    int x0 = p.x >= split ? split : 0;
    ivec2 pane = ivec2(p.x >= split ? size.x - split : split, size.y);
    vec2 t = texelFetch(targets, ivec2(p.x, size.y - 1 - p.y), 0).xy;
    if (!(t.x >= 0.0 && t.x <= float(pane.x) && t.y >= 0.0 && t.y <= float(pane.y))) {
        colour = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    vec2 g = clamp(t - 0.5, vec2(0.0), vec2(pane - 1));
    ivec2 i0 = ivec2(g), i1 = min(i0 + 1, pane - 1);
    vec2 f = g - vec2(i0);
    vec3 top = texel(x0 + i0.x, i0.y) * 255.0 + f.x * (texel(x0 + i1.x, i0.y) - texel(x0 + i0.x, i0.y)) * 255.0;
    vec3 bottom = texel(x0 + i0.x, i1.y) * 255.0 + f.x * (texel(x0 + i1.x, i1.y) - texel(x0 + i0.x, i1.y)) * 255.0;
    colour = vec4((top + f.y * (bottom - top)) / 255.0, 1.0);
}
