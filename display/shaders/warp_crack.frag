#version 330 core
// The GL re-projection, passes 2 and 3: one-pixel cracks of a splat closed as the CPU warp's
// fillCracks does. An uncovered pixel between two covered ones (left and right, else above and
// below; the two inward at the image's edge) whose depths are within `ratio` takes the nearer.
// Pass 1 joins splatted pixels only (covered 1) and marks its fills 2; pass 2 also joins those
// and marks its fills 3. Each pass reads the state before it and writes a new one.
uniform sampler2D state;  // RGBA8: rgb, alpha covered / 255
uniform sampler2D depth;  // R32F
uniform int pass;
uniform float ratio;
layout(location = 0) out vec4 outState;
layout(location = 1) out float outDepth;

int coveredAt(ivec2 p) { return int(round(texelFetch(state, p, 0).a * 255.0)); }

bool joins(ivec2 a, ivec2 b) {
    int ca = coveredAt(a), cb = coveredAt(b);
    if (ca == 0 || ca > pass || cb == 0 || cb > pass) return false;
    float da = texelFetch(depth, a, 0).r, db = texelFetch(depth, b, 0).r;
    return max(da, db) <= min(da, db) * ratio;
}

// The two neighbours of `p` along `step` (its coordinate c of n); at the edge the two inward.
bool neighbours(int c, int n, ivec2 p, ivec2 step, out ivec2 a, out ivec2 b) {
    a = p;
    b = p;
    if (n < 3) return false;
    if (c == 0) {
        a = p + step;
        b = p + 2 * step;
    } else if (c == n - 1) {
        a = p - step;
        b = p - 2 * step;
    } else {
        a = p - step;
        b = p + step;
    }
    return true;
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy), size = textureSize(state, 0);
    outState = texelFetch(state, p, 0);
    outDepth = texelFetch(depth, p, 0).r;
    if (coveredAt(p) != 0) return;
    ivec2 a, b;
    bool across = neighbours(p.x, size.x, p, ivec2(1, 0), a, b) && joins(a, b);
    if (!across && !(neighbours(p.y, size.y, p, ivec2(0, 1), a, b) && joins(a, b))) return;
    ivec2 from = texelFetch(depth, b, 0).r < texelFetch(depth, a, 0).r ? b : a;
    outState = vec4(texelFetch(state, from, 0).rgb, float(pass + 1) / 255.0);
    outDepth = texelFetch(depth, from, 0).r;
}
