#version 330 core
// The GL re-projection's last pass: a hole of both views (filled) takes the nearest known pixel
// of its row on the side whose depth is farther (a disocclusion uncovers what lies behind the
// edge), the left one of equals, the only one when one side has none; a row without any known
// pixel takes the nearest row that has some (the one above of two as near), as that row is
// filled; the background colour only when no row has any: the CPU warp's fallback. With `debug`
// every pixel is then tinted by its origin as warpDebugColours does, (colour + tint + 1) / 2 in
// whole levels.
uniform sampler2D composed;       // rgb, alpha: the WarpPixel / 255
uniform sampler2D composedDepth;
uniform isampler2D sides;
uniform isampler2D rows;          // per row: the nearest row with a known pixel above, below
uniform vec3 background;          // WarpOptions::background / 255
uniform bool debug;
uniform ivec3 tints[4];           // kWarpTints
out vec4 outColour;               // rgb, alpha: the WarpPixel / 255

// The row fill of pixel p (a hole of both views).
vec3 rowFill(ivec2 p, int width) {
    ivec2 s = texelFetch(sides, p, 0).xy;
    int l = s.x, r = s.y < width ? s.y : -1;
    int from = l;
    if (l < 0) from = r;
    else if (r >= 0 && texelFetch(composedDepth, ivec2(r, p.y), 0).r > texelFetch(composedDepth, ivec2(l, p.y), 0).r) from = r;
    return from < 0 ? background : texelFetch(composed, ivec2(from, p.y), 0).rgb;
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(composed, 0);
    vec4 c = texelFetch(composed, p, 0);
    int origin = int(round(c.a * 255.0));
    vec3 rgb = c.rgb;
    if (origin == 3) {
        ivec2 q = p;
        ivec2 near = texelFetch(rows, ivec2(0, p.y), 0).xy;
        if (near.x != p.y) {  // no pixel of this row came from a view
            bool above = near.x >= 0, below = near.y < size.y;
            if (above || below) q.y = !below || (above && p.y - near.x <= near.y - p.y) ? near.x : near.y;
        }
        vec4 cq = texelFetch(composed, q, 0);
        rgb = int(round(cq.a * 255.0)) == 3 ? rowFill(q, size.x) : cq.rgb;
    }
    if (debug) {
        ivec3 v = ivec3(round(rgb * 255.0));
        rgb = vec3((v + tints[origin] + 1) / 2) / 255.0;
    }
    outColour = vec4(rgb, c.a);
}
