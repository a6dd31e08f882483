#version 330 core
// The GL re-projection's row scans: after the passes with step 1, 2, 4, ... each pixel knows the
// nearest known column of its row within twice the last step on either side (the larger known
// column of two windows on the left, the smaller on the right), so ceil(log2(width)) passes
// find them in the whole row.
uniform isampler2D sides;
uniform int step;
out ivec2 outSides;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int width = textureSize(sides, 0).x;
    ivec2 s = texelFetch(sides, p, 0).xy;
    if (p.x - step >= 0) s.x = max(s.x, texelFetch(sides, ivec2(p.x - step, p.y), 0).x);
    if (p.x + step < width) s.y = min(s.y, texelFetch(sides, ivec2(p.x + step, p.y), 0).y);
    outSides = s;
}
