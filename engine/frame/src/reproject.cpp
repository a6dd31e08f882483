// Forward warp by depth-tested point splats: every source pixel is one point, put back into
// the world at its depth and written into the target pixel that contains its projection, the
// nearest point winning. Splats rather than a grid mesh: each target pixel takes exactly one
// source pixel's bytes (no interpolation blurs texture or breaks bit identity), a silhouette
// never drags a rubber sheet across a disocclusion (a mesh must guess which neighbours to
// connect), and what no point reaches is exactly the hole. What a mesh does better, closing
// the cracks of a magnified surface, the crack rule below does for gaps of one pixel.
#include <rtwall/reproject.h>
#include <rtwall/vec.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace rtwall {

namespace {

// Where world points land in a camera's image: direction(px, py) = corner + du px + dv py, so
// a point p seen from the origin solves p - origin = s (du px + dv py + corner): px = a / c,
// py = b / c for (a, b, c) = M^-1 (p - origin), M = [du dv corner], in front where c > 0.
struct Projector {
    double origin[3];
    double inv[3][3];
    int width, height;

    Projector(const CameraDesc& desc, int w, int h) : width(w), height(h) {
        const Camera camera(desc, w, h);
        const Float3 o = camera.origin(), u = camera.du(), v = camera.dv(), c = camera.corner();
        origin[0] = o.x, origin[1] = o.y, origin[2] = o.z;
        const double m[3][3] = {{u.x, v.x, c.x}, {u.y, v.y, c.y}, {u.z, v.z, c.z}};
        const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        const double r = det != 0.0 ? 1.0 / det : 0.0;  // a degenerate camera sees nothing
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                // The cofactor of m[j][i]: the inverse is the adjugate over the determinant.
                const int a0 = (j + 1) % 3, a1 = (j + 2) % 3, b0 = (i + 1) % 3, b1 = (i + 2) % 3;
                inv[i][j] = (m[a0][b0] * m[a1][b1] - m[a0][b1] * m[a1][b0]) * r;
            }
    }
    // The pixel that sees direction `d` (from the origin); false when behind or outside.
    bool pixelOf(const double d[3], int& px, int& py) const {
        const double a = inv[0][0] * d[0] + inv[0][1] * d[1] + inv[0][2] * d[2];
        const double b = inv[1][0] * d[0] + inv[1][1] * d[1] + inv[1][2] * d[2];
        const double c = inv[2][0] * d[0] + inv[2][1] * d[1] + inv[2][2] * d[2];
        if (!(c > 0.0)) return false;
        const double x = std::floor(a / c), y = std::floor(b / c);
        if (!(x >= 0.0 && x < double(width) && y >= 0.0 && y < double(height))) return false;
        px = int(x), py = int(y);
        return true;
    }
};

void sizeSplat(Reprojector::Splat& s, int w, int h) {
    const size_t n = size_t(w) * size_t(h);
    s.image.width = w;
    s.image.height = h;
    s.image.rgb.resize(n * 3);
    s.depth.assign(n, kBackgroundDepth);
    s.covered.assign(n, 0);
}

void checkSource(const WarpSource& s, const char* which) {
    const size_t n = size_t(std::max(0, s.image.width)) * size_t(std::max(0, s.image.height));
    if (s.depth.size() != n || s.image.rgb.size() != n * 3)
        throw std::invalid_argument(std::string("reproject: the ") + which + " view has " +
                                    std::to_string(s.depth.size()) + " depths and " + std::to_string(s.image.rgb.size()) +
                                    " colour bytes for " + std::to_string(s.image.width) + "x" +
                                    std::to_string(s.image.height) + " pixels");
}

// Every pixel of `src` with a depth into `out` (sized for `to`), nearest first; background
// pixels are directions (points at infinity), behind every surface.
void splat(const WarpSource& src, const Projector& to, Reprojector::Splat& out) {
    const int sw = src.image.width, sh = src.image.height;
    const Camera from(src.camera, sw, sh);
    const Float3 o = from.origin();
    const double shift[3] = {double(o.x) - to.origin[0], double(o.y) - to.origin[1], double(o.z) - to.origin[2]};
    for (int y = 0; y < sh; ++y)
        for (int x = 0; x < sw; ++x) {
            const size_t i = size_t(y) * size_t(sw) + size_t(x);
            const float depth = src.depth[i];
            const bool background = depth == kBackgroundDepth;
            if (!background && !(depth > 0.0f && std::isfinite(depth))) continue;  // no depth: a hole
            const Float3 d = from.direction(float(x) + 0.5f, float(y) + 0.5f);
            const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
            const double s = background ? 1.0 / len : double(depth) / len;
            double p[3] = {d.x * s, d.y * s, d.z * s};
            if (!background)
                for (int k = 0; k < 3; ++k) p[k] += shift[k];
            int tx, ty;
            if (!to.pixelOf(p, tx, ty)) continue;
            const size_t t = size_t(ty) * size_t(to.width) + size_t(tx);
            const float dist = background ? kBackgroundDepth : float(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
            if (out.covered[t] && !(dist < out.depth[t])) continue;  // the first of equals stays
            out.covered[t] = 1;
            out.depth[t] = dist;
            std::memcpy(&out.image.rgb[t * 3], &src.image.rgb[i * 3], 3);
        }
}

// The two neighbours of coordinate `c` (of `n`) along one axis whose pixel indices are
// `i` -/+ `step`; at the image's edge, the two next inward (a crack along the edge has only one
// side). False where the axis is too short.
bool neighbours(int c, int n, size_t i, size_t step, size_t& a, size_t& b) {
    if (n < 3) return false;
    if (c == 0) a = i + step, b = i + 2 * step;
    else if (c == n - 1) a = i - step, b = i - 2 * step;
    else a = i - step, b = i + step;
    return true;
}

// Fills the one-pixel cracks of `s`: an uncovered pixel between two splatted ones (left and
// right, else above and below; the two inward at the edge) at depths within `ratio` takes the
// nearer of them. Pass 1 joins splatted pixels only (covered 1) and marks its fills 2; pass 2
// also joins those and marks its fills 3, closing where a crack row meets a crack column. Each
// pass reads only what the passes before it wrote, so the order within a pass does not matter.
void fillCracks(Reprojector::Splat& s, float ratio, uint8_t pass) {
    const int w = s.image.width, h = s.image.height;
    auto joins = [&](size_t a, size_t b) {
        if (s.covered[a] == 0 || s.covered[a] > pass || s.covered[b] == 0 || s.covered[b] > pass) return false;
        const float lo = std::min(s.depth[a], s.depth[b]), hi = std::max(s.depth[a], s.depth[b]);
        return hi <= lo * ratio;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            if (s.covered[i]) continue;
            size_t a, b;
            const bool across = neighbours(x, w, i, 1, a, b) && joins(a, b);
            if (!across && !(neighbours(y, h, i, size_t(w), a, b) && joins(a, b))) continue;
            const size_t from = s.depth[b] < s.depth[a] ? b : a;
            s.covered[i] = uint8_t(pass + 1);
            s.depth[i] = s.depth[from];
            std::memcpy(&s.image.rgb[i * 3], &s.image.rgb[from * 3], 3);
        }
}

void copyPixel(const Reprojector::Splat& from, size_t i, WarpedView& to, size_t t) {
    std::memcpy(&to.image.rgb[t * 3], &from.image.rgb[i * 3], 3);
    to.depth[t] = from.depth[i];
}

}  // namespace

bool samePose(const CameraDesc& a, const CameraDesc& b) {
    return a.position == b.position && a.lookAt == b.lookAt && a.up == b.up && a.fovY == b.fovY && a.window == b.window;
}

const WarpedView& Reprojector::warp(const WarpSource& newest, const CameraDesc& target, const WarpSource* older,
                                    const WarpOptions& options) {
    checkSource(newest, "newest");
    if (older) checkSource(*older, "older");
    const int w = newest.image.width, h = newest.image.height;
    const size_t n = size_t(w) * size_t(h);
    out_.image.width = w;
    out_.image.height = h;
    out_.image.rgb.resize(n * 3);
    out_.depth.resize(n);
    out_.holes = 0;
    if (options.copySamePose && samePose(newest.camera, target)) {
        std::copy(newest.image.rgb.begin(), newest.image.rgb.end(), out_.image.rgb.begin());
        std::copy(newest.depth.begin(), newest.depth.end(), out_.depth.begin());
        out_.mask.assign(n, WarpPixel::Fresh);
        return out_;
    }
    const Projector to(target, w, h);
    sizeSplat(newest_, w, h);
    splat(newest, to, newest_);
    for (uint8_t pass : {1, 2}) fillCracks(newest_, options.crackRatio, pass);
    if (older) {
        sizeSplat(older_, w, h);
        splat(*older, to, older_);
        for (uint8_t pass : {1, 2}) fillCracks(older_, options.crackRatio, pass);
    }
    out_.mask.resize(n);
    for (size_t i = 0; i < n; ++i) {
        if (newest_.covered[i]) {
            copyPixel(newest_, i, out_, i);
            out_.mask[i] = WarpPixel::Warped;
            continue;
        }
        ++out_.holes;
        const bool fromOlder = older && older_.covered[i];
        if (fromOlder) copyPixel(older_, i, out_, i);
        out_.mask[i] = fromOlder ? WarpPixel::Older : WarpPixel::Filled;
    }
    fillHoles(options);
    return out_;
}

// The fallback: a pixel neither view covers takes the nearest covered pixel of its row on the
// side whose depth is farther (a disocclusion uncovers what lies behind the edge, so the far
// side continues it; the near side is the occluder that moved away), the left one of equals,
// the only one when one side has none, the background colour when the row has none.
void Reprojector::fillHoles(const WarpOptions& options) {
    const int w = out_.image.width, h = out_.image.height;
    left_.resize(size_t(std::max(0, w)));
    right_.resize(size_t(std::max(0, w)));
    for (int y = 0; y < h; ++y) {
        const size_t row = size_t(y) * size_t(w);
        auto known = [&](int x) { return out_.mask[row + size_t(x)] != WarpPixel::Filled; };
        for (int x = 0, last = -1; x < w; ++x) left_[size_t(x)] = last = known(x) ? x : last;
        for (int x = w - 1, last = -1; x >= 0; --x) right_[size_t(x)] = last = known(x) ? x : last;
        for (int x = 0; x < w; ++x) {
            if (known(x)) continue;
            const int l = left_[size_t(x)], r = right_[size_t(x)];
            const size_t t = row + size_t(x);
            if (l < 0 && r < 0) {
                std::memcpy(&out_.image.rgb[t * 3], options.background, 3);
                out_.depth[t] = kBackgroundDepth;
                continue;
            }
            const int from = l < 0 ? r : r < 0 ? l : out_.depth[row + size_t(r)] > out_.depth[row + size_t(l)] ? r : l;
            std::memcpy(&out_.image.rgb[t * 3], &out_.image.rgb[(row + size_t(from)) * 3], 3);
            out_.depth[t] = out_.depth[row + size_t(from)];
        }
    }
}

void warpDebugColours(const WarpedView& view, Image& out) {
    static constexpr uint8_t kTint[4][3] = {{0, 200, 0}, {40, 90, 255}, {255, 220, 0}, {255, 0, 0}};
    out.width = view.image.width;
    out.height = view.image.height;
    out.rgb.resize(view.image.rgb.size());
    for (size_t i = 0; i < view.mask.size(); ++i)
        for (int c = 0; c < 3; ++c)
            out.rgb[i * 3 + size_t(c)] =
                uint8_t((int(view.image.rgb[i * 3 + size_t(c)]) + int(kTint[size_t(view.mask[i])][c]) + 1) / 2);
}

WarpTiming timeReprojection(int width, int height, int runs) {
    // A view of a slanted floor with a raised block and sky above, rendered from 2 m away; the
    // head then moves 5 cm right and 2 cm forward and turns by a degree.
    CameraDesc from;
    from.position = {0, 1.6f, 2};
    from.lookAt = {0, 1.2f, 0};
    CameraDesc to = from;
    to.position = {0.05f, 1.6f, 1.98f};
    to.lookAt = {0.1f, 1.2f, 0};
    Image image;
    image.width = width;
    image.height = height;
    image.rgb.resize(size_t(width) * size_t(height) * 3);
    std::vector<float> depth(size_t(width) * size_t(height));
    const Camera camera(from, width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            const Float3 d = camera.direction(float(x) + 0.5f, float(y) + 0.5f);
            const bool block = x > width / 3 && x < width / 2 && y > height / 2;
            const float floorAt = d.y < 0 ? -(block ? 1.3f : 1.6f) / d.y * std::sqrt(dot(d, d)) : kBackgroundDepth;
            depth[i] = floorAt;
            for (int c = 0; c < 3; ++c) image.rgb[i * 3 + size_t(c)] = uint8_t((x * 7 + y * 3 + c * 50) & 0xFF);
        }
    Reprojector warper;
    std::vector<double> ms;
    for (int r = 0; r < runs; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        warper.warp({image, depth, from}, to, nullptr, {});
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    WarpTiming t;
    t.runs = runs;
    if (runs > 0) {
        std::sort(ms.begin(), ms.end());
        t.medianMs = ms.size() % 2 ? ms[ms.size() / 2] : 0.5 * (ms[ms.size() / 2 - 1] + ms[ms.size() / 2]);
        t.p95Ms = ms[std::min(ms.size() - 1, size_t(std::ceil(0.95 * double(ms.size()))) - 1)];
    }
    return t;
}

}  // namespace rtwall
