#version 330 core
// A calibrated projector's blend (issue 30; ProjectorBlendStage, whose apply() is the CPU
// reference): the screen's pixels as drawn, in linear light, times the alpha map, over the
// beta map's black level, encoded again: out = beta + (1 - beta) alpha in. Where alpha is 1 and
// beta 0 the pixel is left as it is (bit for bit, as the CPU does).
uniform sampler2D shown;     // a copy of the screen's back buffer (GL rows: bottom first)
uniform sampler2D alphaMap;  // RGB32F, linear, one texel per screen pixel, row 0 the top row
uniform sampler2D betaMap;
uniform int screenHeight;
out vec4 colour;

float decode(float s) { return s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4); }
float encode(float l) { return l <= 0.0031308 ? l * 12.92 : 1.055 * pow(l, 1.0 / 2.4) - 0.055; }

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 c = texelFetch(shown, p, 0).rgb;
    ivec2 m = ivec2(p.x, screenHeight - 1 - p.y);
    vec3 a = texelFetch(alphaMap, m, 0).rgb, b = texelFetch(betaMap, m, 0).rgb;
    vec3 o = c;
    for (int k = 0; k < 3; ++k)
        if (a[k] != 1.0 || b[k] != 0.0) o[k] = clamp(encode(b[k] + (1.0 - b[k]) * a[k] * decode(c[k])), 0.0, 1.0);
    colour = vec4(o, 1.0);
}
