#version 330 core
// The GL re-projection (display/src/gl_reproject.cpp), pass 1: one point per source pixel
// (gl_VertexID = y * width + x), put where the target camera sees it. The arithmetic is the CPU
// warp's (engine/frame/src/reproject.cpp, splatRows) in float: the ray through the pixel's
// centre, the point at its depth along it, its (a, b, c) in the target camera, the pixel
// floor(a / c, b / c). A point behind the camera, outside the image or without a depth is
// placed outside the clip volume and draws nothing.
uniform sampler2D sourceColour;  // RGB8, image row y in texture row y
uniform sampler2D sourceDepth;   // R32F: kBackgroundDepth background; not finite or <= 0: no depth
uniform ivec2 sourceSize;
uniform ivec2 targetSize;
uniform vec3 corner, du, dv;     // the source camera's rays: corner + du px + dv py
uniform vec3 shift;              // the source camera's origin minus the target's
uniform vec3 solvedCorner, solvedDu, solvedDv, solvedShift;  // each solved in the target camera
uniform float keyScale;          // 2^-64: squared distances of 1e-12 to 1e12 stay normal floats below 1
flat out vec3 colour;
flat out float distance;
flat out float key;

const float kBackground = 3.40282347e38;  // kBackgroundDepth, the largest float
const float kBackgroundKey = 0.99999994;  // the largest float below 1: behind every surface, before the clear

void main() {
    int x = gl_VertexID % sourceSize.x, y = gl_VertexID / sourceSize.x;
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    float depth = texelFetch(sourceDepth, ivec2(x, y), 0).r;
    // By the bits, so that no compiler's NaN shortcuts decide what is a depth.
    uint bits = floatBitsToUint(depth);
    bool background = depth == kBackground;
    bool finite = (bits & 0x7f800000u) != 0x7f800000u;
    bool positive = (bits & 0x80000000u) == 0u && (bits & 0x7fffffffu) != 0u;
    if (!background && !(finite && positive)) return;
    float px = float(x) + 0.5, py = float(y) + 0.5;
    vec3 d = corner + du * px + dv * py;
    float s = (background ? 1.0 : depth) / length(d);
    // A direction (background) does not move with the origin.
    vec3 solved = s * (solvedCorner + solvedDu * px + solvedDv * py) + (background ? vec3(0.0) : solvedShift);
    if (!(solved.z > 0.0)) return;
    vec2 f = solved.xy * (1.0 / solved.z);
    if (!(f.x >= 0.0 && f.x < float(targetSize.x) && f.y >= 0.0 && f.y < float(targetSize.y))) return;
    gl_Position = vec4((floor(f) + 0.5) / vec2(targetSize) * 2.0 - 1.0, 0.0, 1.0);
    colour = texelFetch(sourceColour, ivec2(x, y), 0).rgb;
    vec3 p = d * s + shift;
    float squared = dot(p, p);
    distance = background ? kBackground : sqrt(squared);
    key = background ? kBackgroundKey : min(squared * keyScale, 0.99999988);
}
