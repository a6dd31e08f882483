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
#include <atomic>
#include <barrier>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

namespace rtwall {

namespace {

// A target camera's image: where a solved point (rtwall/warp.h, ImageProjection) lands.
struct Projector : ImageProjection {
    using ImageProjection::ImageProjection;
    // The pixel that sees the point solving to (a, b, c); false when behind or outside. One
    // division (1 / c, then two products) where a / c and b / c would take two: the quotients
    // differ from the divided ones by an ulp at most, which moves a point only when it lies
    // within about 1e-12 pixels of a pixel's edge.
    bool pixelOf(double a, double b, double c, int& px, int& py) const {
        if (!(c > 0.0)) return false;
        const double r = 1.0 / c, x = a * r, y = b * r;
        // Inside [0, width) x [0, height) before the floor: then truncation is the floor.
        if (!(x >= 0.0 && x < double(width) && y >= 0.0 && y < double(height))) return false;
        px = int(x), py = int(y);
        return true;
    }
};

// A target pixel's winner so far, as one number: the point's squared distance (as a float,
// whose bits order like the floats for non-negative values) above its source pixel's index.
// The smallest key is the nearest point and, of equals, the first in row order: the rule a
// single pass in row order keeps (a later point replaces only a farther one), so any number of
// threads splatting in any order find the same winner. Squared, because the square root is
// then taken once per target pixel (resolveRows), not once per source pixel.
constexpr uint64_t kNoSplat = ~uint64_t(0);
// Surfaces stay nearer than the background (kBackgroundDepth, the largest float) however far.
const float kFarthestSurface = std::nextafter(kBackgroundDepth, 0.0f);

uint64_t splatKey(float squaredDistance, size_t source) {
    return uint64_t(std::bit_cast<uint32_t>(squaredDistance)) << 32 | uint64_t(uint32_t(source));
}

void sizeSplat(Reprojector::Splat& s, std::vector<uint64_t>& keys, int w, int h) {
    const size_t n = size_t(w) * size_t(h);
    s.image.width = w;
    s.image.height = h;
    s.image.rgb.resize(n * 3);
    s.depth.resize(n);
    s.covered.resize(n);
    keys.resize(n);
}

// Source rows [y0, y1) of `src` into `keys` (sized for `to`): each pixel with a depth becomes a
// key in the target pixel that sees it, the smallest key staying; background pixels are
// directions (points at infinity), behind every surface. `shared`: other threads write the same
// keys (an atomic minimum), else a plain one.
template <bool shared>
void splatRows(const WarpSource& src, const Projector& to, uint64_t* keys, int y0, int y1, int x0, int x1, const TileRect& into) {
    const int sw = src.image.width;
    const Camera from(src.camera, sw, src.image.height);
    const Float3 o = from.origin(), fc = from.corner(), fu = from.du(), fv = from.dv();
    // Pixel (x, y)'s ray is d = row + du px (px = x + 0.5, row = corner + dv (y + 0.5)), in
    // double. Its point at distance `depth` is p = d s + shift (s = depth / |d|; shift: from the
    // target's origin to the source's), so p's (a, b, c) is s (R + X px) + S with R, X, S the
    // solved row, du and shift, and |p|^2 = depth^2 + 2 s (d . shift) + |shift|^2: a few
    // products per pixel, each linear or quadratic in px.
    const double shift[3] = {double(o.x) - to.origin[0], double(o.y) - to.origin[1], double(o.z) - to.origin[2]};
    const double du[3] = {fu.x, fu.y, fu.z};
    double solvedDu[3], solvedShift[3];
    to.solve(du, solvedDu);
    to.solve(shift, solvedShift);
    const double duDu = du[0] * du[0] + du[1] * du[1] + du[2] * du[2];
    const double duShift = du[0] * shift[0] + du[1] * shift[1] + du[2] * shift[2];
    const double shiftShift = shift[0] * shift[0] + shift[1] * shift[1] + shift[2] * shift[2];
    for (int y = y0; y < y1; ++y) {
        const double py = double(y) + 0.5;
        const double row[3] = {fc.x + fv.x * py, fc.y + fv.y * py, fc.z + fv.z * py};
        double r[3];
        to.solve(row, r);
        const double rowRow = row[0] * row[0] + row[1] * row[1] + row[2] * row[2];
        const double rowDu2 = 2.0 * (row[0] * du[0] + row[1] * du[1] + row[2] * du[2]);
        const double rowShift = row[0] * shift[0] + row[1] * shift[1] + row[2] * shift[2];
        for (int x = x0; x < x1; ++x) {
            const size_t i = size_t(y) * size_t(sw) + size_t(x);
            const float depth = src.depth[i];
            const bool background = depth == kBackgroundDepth;
            if (!background && !(depth > 0.0f && std::isfinite(depth))) continue;  // no depth: a hole
            const double px = double(x) + 0.5;
            const double s = (background ? 1.0 : double(depth)) / std::sqrt(rowRow + px * (rowDu2 + px * duDu));
            const double k = background ? 0.0 : 1.0;  // a direction does not move with the origin
            int tx, ty;
            if (!to.pixelOf(s * (r[0] + solvedDu[0] * px) + k * solvedShift[0], s * (r[1] + solvedDu[1] * px) + k * solvedShift[1],
                            s * (r[2] + solvedDu[2] * px) + k * solvedShift[2], tx, ty) ||
                tx < into.x0 || tx >= into.x1 || ty < into.y0 || ty >= into.y1)
                continue;
            const double dd = double(depth);
            const float squared =
                background ? kBackgroundDepth
                           : std::clamp(float(dd * dd + 2.0 * s * (rowShift + duShift * px) + shiftShift), 0.0f, kFarthestSurface);
            const uint64_t key = splatKey(squared, i);
            uint64_t& slot = keys[size_t(ty) * size_t(to.width) + size_t(tx)];
            if constexpr (shared) {
                std::atomic_ref<uint64_t> atomic(slot);
                uint64_t seen = atomic.load(std::memory_order_relaxed);
                while (key < seen && !atomic.compare_exchange_weak(seen, key, std::memory_order_relaxed)) {
                }
            } else if (key < slot) {
                slot = key;
            }
        }
    }
}

// Target rows [y0, y1): each key's source pixel (bytes and distance) into the splat image.
void resolveRows(const WarpSource& src, const uint64_t* keys, Reprojector::Splat& s, int y0, int y1, const TileRect& r) {
    const size_t w = size_t(s.image.width);
    for (int y = y0; y < y1; ++y)
    for (size_t t = size_t(y) * w + size_t(r.x0); t < size_t(y) * w + size_t(r.x1); ++t) {
        const uint64_t key = keys[t];
        s.covered[t] = key != kNoSplat;
        if (key == kNoSplat) {
            s.depth[t] = kBackgroundDepth;
            continue;
        }
        const float squared = std::bit_cast<float>(uint32_t(key >> 32));
        s.depth[t] = squared == kBackgroundDepth ? kBackgroundDepth : std::sqrt(squared);
        std::memcpy(&s.image.rgb[t * 3], &src.image.rgb[size_t(uint32_t(key)) * 3], 3);
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

// Fills the one-pixel cracks of rows [y0, y1) of `s`: an uncovered pixel between two splatted
// ones (left and right, else above and below; the two inward at the edge) at depths within
// `ratio` takes the nearer of them. Pass 1 joins splatted pixels only (covered 1) and marks its
// fills 2; pass 2 also joins those and marks its fills 3, closing where a crack row meets a
// crack column. Each pass reads only what the passes before it wrote, so the order within a
// pass does not matter and threads may fill rows side by side.
void fillCracks(Reprojector::Splat& s, float ratio, uint8_t pass, int y0, int y1, const TileRect& r) {
    const int w = s.image.width;
    auto joins = [&](size_t a, size_t b) {
        if (s.covered[a] == 0 || s.covered[a] > pass || s.covered[b] == 0 || s.covered[b] > pass) return false;
        const float lo = std::min(s.depth[a], s.depth[b]), hi = std::max(s.depth[a], s.depth[b]);
        return hi <= lo * ratio;
    };
    for (int y = y0; y < y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            if (s.covered[i]) continue;
            size_t a, b;
            const bool across = neighbours(x - r.x0, r.width(), i, 1, a, b) && joins(a, b);
            if (!across && !(neighbours(y - r.y0, r.height(), i, size_t(w), a, b) && joins(a, b))) continue;
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

// Target row `y` of `out` from the two splats: the newest view where it covers, else the older,
// else the fallback: a pixel neither covers takes the nearest covered pixel of its row on the
// side whose depth is farther (a disocclusion uncovers what lies behind the edge, so the far
// side continues it; the near side is the occluder that moved away), the left one of equals,
// the only one when one side has none, the background colour when the row has none (fillRows
// then gives it the nearest row's). Returns the row's holes (pixels the newest view left
// uncovered); `known`: whether any pixel of the row came from a view.
size_t composeRow(const Reprojector::Splat& newest, const Reprojector::Splat* older, const WarpOptions& options,
                  WarpedView& out, int y, const TileRect& region, uint8_t& known) {
    const int w = out.image.width;
    const size_t row = size_t(y) * size_t(w);
    size_t holes = 0, fromOlderCount = 0;
    for (size_t i = row + size_t(region.x0); i < row + size_t(region.x1); ++i) {
        if (newest.covered[i]) {
            copyPixel(newest, i, out, i);
            out.mask[i] = WarpPixel::Warped;
            continue;
        }
        ++holes;
        const bool fromOlder = older && older->covered[i];
        if (fromOlder) copyPixel(*older, i, out, i);
        fromOlderCount += fromOlder;
        out.mask[i] = fromOlder ? WarpPixel::Older : WarpPixel::Filled;
    }
    known = holes < size_t(region.width()) || fromOlderCount > 0;
    if (holes == 0) return 0;
    // Runs of Filled pixels between known ones: every pixel of a run has the same two sides.
    for (int x = region.x0; x < region.x1;) {
        if (out.mask[row + size_t(x)] != WarpPixel::Filled) {
            ++x;
            continue;
        }
        const int l = x > region.x0 ? x - 1 : -1;
        int r = x;
        while (r < region.x1 && out.mask[row + size_t(r)] == WarpPixel::Filled) ++r;
        const int end = r;
        if (r == region.x1) r = -1;
        const int from = l < 0 ? r : r < 0 ? l : out.depth[row + size_t(r)] > out.depth[row + size_t(l)] ? r : l;
        for (; x < end; ++x) {
            const size_t t = row + size_t(x);
            if (from < 0) {
                std::memcpy(&out.image.rgb[t * 3], options.background, 3);
                out.depth[t] = kBackgroundDepth;
            } else {
                std::memcpy(&out.image.rgb[t * 3], &out.image.rgb[(row + size_t(from)) * 3], 3);
                out.depth[t] = out.depth[row + size_t(from)];
            }
        }
    }
    return holes;
}

// A row of `region` that no view covered anywhere (a whole row at the edge the head moved
// towards: neither frame saw it) takes the nearest row that one did, as the row fill left it
// (the one above of two as near); the background colour stays only where no row was covered.
// After every row of the region was composed (composeRow's `known`).
void fillRows(WarpedView& out, const std::vector<uint8_t>& known, const TileRect& region, int y0, int y1) {
    const size_t w = size_t(out.image.width);
    for (int y = y0; y < y1; ++y) {
        if (known[size_t(y)]) continue;
        int above = y - 1, below = y + 1;
        while (above >= region.y0 && !known[size_t(above)]) --above;
        while (below < region.y1 && !known[size_t(below)]) ++below;
        const bool hasAbove = above >= region.y0, hasBelow = below < region.y1;
        if (!hasAbove && !hasBelow) continue;
        const int from = !hasBelow || (hasAbove && y - above <= below - y) ? above : below;
        const size_t x0 = size_t(region.x0), n = size_t(region.width());
        std::memcpy(&out.image.rgb[(size_t(y) * w + x0) * 3], &out.image.rgb[(size_t(from) * w + x0) * 3], n * 3);
        std::memcpy(&out.depth[size_t(y) * w + x0], &out.depth[size_t(from) * w + x0], n * sizeof(float));
    }
}

// Rows [0, n) split evenly over `threads` parts: part `i`'s first and end row.
std::pair<int, int> rowsOf(int n, int threads, int i) {
    return {int(int64_t(n) * i / threads), int(int64_t(n) * (i + 1) / threads)};
}

}  // namespace

const WarpedView& Reprojector::warp(const WarpSource& newest, const CameraDesc& target, const WarpSource* older,
                                    const WarpOptions& options) {
    checkWarpSource(newest, "newest");
    if (older) checkWarpSource(*older, "older");
    const int w = newest.image.width, h = newest.image.height;
    const size_t n = size_t(w) * size_t(h);
    out_.image.width = w;
    out_.image.height = h;
    out_.image.rgb.resize(n * 3);
    out_.depth.resize(n);
    out_.mask.resize(n);
    out_.holes = 0;
    if (options.copySamePose && samePose(newest.camera, target)) {
        std::copy(newest.image.rgb.begin(), newest.image.rgb.end(), out_.image.rgb.begin());
        std::copy(newest.depth.begin(), newest.depth.end(), out_.depth.begin());
        std::fill(out_.mask.begin(), out_.mask.end(), WarpPixel::Fresh);
        return out_;
    }
    // The part warped: the region, clipped; all of the view without one.
    TileRect region{0, 0, w, h};
    if (const std::optional<TileRect>& r = options.region)
        region = {std::clamp(r->x0, 0, w), std::clamp(r->y0, 0, h), std::clamp(r->x1, 0, w), std::clamp(r->y1, 0, h)};
    if (region.width() <= 0 || region.height() <= 0) return out_;
    const Projector to(target, w, h);
    sizeSplat(newest_, newestKeys_, w, h);
    if (older) sizeSplat(older_, olderKeys_, w, h);
    const int hardware = int(std::max(1u, std::thread::hardware_concurrency()));
    const int threads = std::clamp(options.threads > 0 ? options.threads : hardware, 1, region.height());
    rowHoles_.assign(size_t(threads), 0);
    rowKnown_.resize(size_t(h));
    // Every thread takes its share of rows through the same phases; a phase reads what the ones
    // before it wrote, so all wait for all between phases. Each phase's result does not depend
    // on how its rows were shared: the bytes are the same for any number of threads.
    std::barrier sync(threads);
    auto phases = [&](int part) {
        auto [y0, y1] = rowsOf(region.height(), threads, part);
        y0 += region.y0;
        y1 += region.y0;
        for (int y = y0; y < y1; ++y) {
            const ptrdiff_t row = ptrdiff_t(size_t(y) * size_t(w));
            std::fill(newestKeys_.begin() + row + region.x0, newestKeys_.begin() + row + region.x1, kNoSplat);
            if (older) std::fill(olderKeys_.begin() + row + region.x0, olderKeys_.begin() + row + region.x1, kNoSplat);
        }
        sync.arrive_and_wait();
        // A source of the target's size: only the region's pixels (a node holds no others).
        auto splatShare = [&](const WarpSource& src, std::vector<uint64_t>& keys) {
            const bool sameSize = src.image.width == w && src.image.height == h;
            const TileRect from = sameSize ? region : TileRect{0, 0, src.image.width, src.image.height};
            auto [s0, s1] = rowsOf(from.height(), threads, part);
            s0 += from.y0;
            s1 += from.y0;
            if (threads > 1) splatRows<true>(src, to, keys.data(), s0, s1, from.x0, from.x1, region);
            else splatRows<false>(src, to, keys.data(), s0, s1, from.x0, from.x1, region);
        };
        splatShare(newest, newestKeys_);
        if (older) splatShare(*older, olderKeys_);
        sync.arrive_and_wait();
        resolveRows(newest, newestKeys_.data(), newest_, y0, y1, region);
        if (older) resolveRows(*older, olderKeys_.data(), older_, y0, y1, region);
        for (uint8_t pass : {1, 2}) {
            sync.arrive_and_wait();
            fillCracks(newest_, options.crackRatio, pass, y0, y1, region);
            if (older) fillCracks(older_, options.crackRatio, pass, y0, y1, region);
        }
        sync.arrive_and_wait();
        for (int y = y0; y < y1; ++y)
            rowHoles_[size_t(part)] += composeRow(newest_, older ? &older_ : nullptr, options, out_, y, region, rowKnown_[size_t(y)]);
        sync.arrive_and_wait();
        fillRows(out_, rowKnown_, region, y0, y1);
    };
    {
        std::vector<std::jthread> helpers;
        for (int part = 1; part < threads; ++part) helpers.emplace_back(phases, part);
        phases(0);
    }
    for (size_t holes : rowHoles_) out_.holes += holes;
    return out_;
}

void warpDebugColours(const WarpedView& view, Image& out) {
    out.width = view.image.width;
    out.height = view.image.height;
    out.rgb.resize(view.image.rgb.size());
    for (size_t i = 0; i < view.mask.size(); ++i)
        for (int c = 0; c < 3; ++c)
            out.rgb[i * 3 + size_t(c)] =
                uint8_t((int(view.image.rgb[i * 3 + size_t(c)]) + int(kWarpTints[size_t(view.mask[i])][c]) + 1) / 2);
}

WarpTiming timeReprojection(int width, int height, int runs, int threads) {
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
    WarpOptions options;
    options.threads = threads;
    std::vector<double> ms;
    for (int r = 0; r < runs; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        warper.warp({image, depth, from}, to, nullptr, options);
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
