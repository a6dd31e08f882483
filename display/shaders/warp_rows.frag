#version 330 core
// The GL re-projection's row fallback, first pass (into a 1 x height target): whether each row
// has a pixel that came from a view (its row scan found one), as the nearest such row above
// (smaller y) and below: (y, y) for such a row, (-1, height) for one without. warp_rowscan.frag
// then spreads them; warp_fill.frag gives a row without any the nearest row's pixels.
uniform isampler2D sides;  // the row scans' result: nearest known column left, right (width: none)
out ivec2 outRows;

void main() {
    int y = int(gl_FragCoord.y);
    ivec2 size = textureSize(sides, 0);
    bool known = texelFetch(sides, ivec2(0, y), 0).y < size.x;
    outRows = known ? ivec2(y, y) : ivec2(-1, size.y);
}
