#version 330 core
// The GL re-projection: the newest view's splat where it covers (warped), else the older
// view's (older), else a hole for the fill (filled); or, for a target at the newest view's own
// pose, the newest view itself (fresh). Also each pixel's own column where it is known, as the
// start of the row scans that find a hole's nearest known pixel on either side.
uniform sampler2D newestState, newestDepth;  // after the crack passes
uniform sampler2D olderState, olderDepth;
uniform bool hasOlder;
uniform bool copySource;                     // the same pose: the source as it is
uniform sampler2D sourceColour;
layout(location = 0) out vec4 outColour;     // rgb, alpha: the WarpPixel / 255
layout(location = 1) out float outDepth;
layout(location = 2) out ivec2 outSides;     // nearest known column left (-1: none) and right (width: none)

const float kFresh = 0.0, kWarped = 1.0, kOlder = 2.0, kFilled = 3.0;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int width = textureSize(newestState, 0).x;
    outSides = ivec2(p.x, p.x);
    outDepth = 0.0;
    if (copySource) {
        outColour = vec4(texelFetch(sourceColour, p, 0).rgb, kFresh / 255.0);
        return;
    }
    vec4 n = texelFetch(newestState, p, 0);
    if (n.a > 0.0) {
        outColour = vec4(n.rgb, kWarped / 255.0);
        outDepth = texelFetch(newestDepth, p, 0).r;
        return;
    }
    if (hasOlder) {
        vec4 o = texelFetch(olderState, p, 0);
        if (o.a > 0.0) {
            outColour = vec4(o.rgb, kOlder / 255.0);
            outDepth = texelFetch(olderDepth, p, 0).r;
            return;
        }
    }
    outColour = vec4(0.0, 0.0, 0.0, kFilled / 255.0);
    outSides = ivec2(-1, width);
}
