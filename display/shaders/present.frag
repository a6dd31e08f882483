#version 330 core
// One screen of the wall: crop (and scale) its viewport out of the wall image, blend its
// overlapping edges, correct gamma and brightness. The CPU reference is display/src/mapping.cpp
// (mapPixel, presentScreen): keep the two in step. A config may give its own fragment shader
// per screen; it gets the same uniforms.
uniform sampler2D wallLeft;   // the wall image (mono, or the left eye); row 0 is the top row
uniform sampler2D wallRight;  // the right eye (the left image again for mono walls)
uniform sampler2D owners;     // one texel per tile: the colour of the client that rendered it
uniform ivec4 viewport;       // x, y, width, height of the screen's part of the wall, wall pixels
uniform ivec2 outputSize;     // the screen's pixels
uniform int eyeMode;          // 0: left or mono, 1: right, 2: side by side (left half, right half)
uniform ivec4 blendWidth;     // ramp widths at the left, right, top, bottom edge, wall pixels
uniform vec4 blendInvGamma;   // 1 / display gamma per edge
uniform float invGamma;       // colour correction: out = brightness * in^invGamma
uniform float brightness;
uniform int tileSize;         // > 0: tint each tile with its client's colour (tiles in frame pixels)
uniform ivec2 wallSize;       // the wall image's pixels
uniform ivec2 frameSize;      // the frame's: the wall's, or fewer (rendered at a fraction, shown upscaled)
out vec4 colour;

float ramp(int width, float d) {
    return clamp(d / float(width), 0.0, 1.0);
}

void main() {
    int ox = int(gl_FragCoord.x);
    int oy = outputSize.y - 1 - int(gl_FragCoord.y);
    int ow = outputSize.x;
    int x = ox;
    int eye = eyeMode;
    if (eyeMode == 2) {
        int halfWidth = ow / 2;
        if (ox >= halfWidth) {
            eye = 1;
            x = ox - halfWidth;
            ow -= halfWidth;
        } else {
            eye = 0;
            ow = halfWidth;
        }
    }
    // Nearest wall pixel to the output pixel's centre, in integers (as mapPixel does).
    int wx = viewport.x + ((2 * x + 1) * viewport.z) / (2 * ow);
    int wy = viewport.y + ((2 * oy + 1) * viewport.w) / (2 * outputSize.y);
    vec3 c;
    if (frameSize == wallSize) {
        c = eye == 1 ? texelFetch(wallRight, ivec2(wx, wy), 0).rgb : texelFetch(wallLeft, ivec2(wx, wy), 0).rgb;
    } else {  // bilinear, the wall pixel's centre in the frame (the textures filter linearly)
        vec2 uv = (vec2(wx, wy) + 0.5) / vec2(wallSize);
        c = eye == 1 ? texture(wallRight, uv).rgb : texture(wallLeft, uv).rgb;
    }
    ivec2 f = ivec2(wx, wy) * frameSize / wallSize;  // the frame pixel the wall pixel scales to
    if (tileSize > 0) c = 0.5 * (c + texelFetch(owners, f / tileSize, 0).rgb);
    float w = 1.0;
    if (blendWidth.x > 0) w *= pow(ramp(blendWidth.x, float(wx - viewport.x) + 0.5), blendInvGamma.x);
    if (blendWidth.y > 0) w *= pow(ramp(blendWidth.y, float(viewport.x + viewport.z - wx) - 0.5), blendInvGamma.y);
    if (blendWidth.z > 0) w *= pow(ramp(blendWidth.z, float(wy - viewport.y) + 0.5), blendInvGamma.z);
    if (blendWidth.w > 0) w *= pow(ramp(blendWidth.w, float(viewport.y + viewport.w - wy) - 0.5), blendInvGamma.w);
    if (invGamma != 1.0) c = pow(c, vec3(invGamma));
    colour = vec4(clamp(c * brightness * w, 0.0, 1.0), 1.0);
}
