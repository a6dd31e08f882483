#version 330 core
// The GL re-projection's row scans (a 1 x height target), as warp_scan.frag does along a row:
// after the passes with step 1, 2, 4, ... each row knows the nearest row with a known pixel
// above (-1: none) and below (height: none).
uniform isampler2D rows;
uniform int step;
out ivec2 outRows;

void main() {
    int y = int(gl_FragCoord.y);
    int height = textureSize(rows, 0).y;
    ivec2 r = texelFetch(rows, ivec2(0, y), 0).xy;
    if (y - step >= 0) r.x = max(r.x, texelFetch(rows, ivec2(0, y - step), 0).x);
    if (y + step < height) r.y = min(r.y, texelFetch(rows, ivec2(0, y + step), 0).y);
    outRows = r;
}
