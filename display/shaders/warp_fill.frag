#version 330 core
// The GL re-projection's last pass: a hole of both views (filled) takes the nearest known pixel
// of its row on the side whose depth is farther (a disocclusion uncovers what lies behind the
// edge), the left one of equals, the only one when one side has none, the background colour
// when the row has none: the CPU warp's fallback. With `debug` every pixel is then tinted by
// its origin as warpDebugColours does, (colour + tint + 1) / 2 in whole levels.
uniform sampler2D composed;       // rgb, alpha: the WarpPixel / 255
uniform sampler2D composedDepth;
uniform isampler2D sides;
uniform vec3 background;          // WarpOptions::background / 255
uniform bool debug;
uniform ivec3 tints[4];           // kWarpTints
out vec4 outColour;               // rgb, alpha: the WarpPixel / 255

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int width = textureSize(composed, 0).x;
    vec4 c = texelFetch(composed, p, 0);
    int origin = int(round(c.a * 255.0));
    vec3 rgb = c.rgb;
    if (origin == 3) {
        ivec2 s = texelFetch(sides, p, 0).xy;
        int l = s.x, r = s.y < width ? s.y : -1;
        int from = l;
        if (l < 0) from = r;
        else if (r >= 0 && texelFetch(composedDepth, ivec2(r, p.y), 0).r > texelFetch(composedDepth, ivec2(l, p.y), 0).r) from = r;
        rgb = from < 0 ? background : texelFetch(composed, ivec2(from, p.y), 0).rgb;
    }
    if (debug) {
        ivec3 v = ivec3(round(rgb * 255.0));
        rgb = vec3((v + tints[origin] + 1) / 2) / 255.0;
    }
    outColour = vec4(rgb, c.a);
}
