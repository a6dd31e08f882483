// A wall's [warp] (issue 30): the MPCDI file checked against the wall it calibrates (`rtwall
// check`), and made into the warps of the views' cameras.
#include <rtwall/display.h>
#include <rtwall/input_error.h>
#include <rtwall/mpcdi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace rtwall {

EyeWindow screenFrame(const WallConfig& wall, size_t screen) {
    const ScreenConfig& s = wall.screens.at(screen);
    EyeWindow f;
    f.eye = wall.stereo.viewer;
    if (s.hasCorners) {
        f.lowerLeft = s.lowerLeft;
        f.right = s.lowerRight - s.lowerLeft;
        f.up = s.upperLeft - s.lowerLeft;
        return f;
    }
    const StereoConfig& st = wall.stereo;
    const Float3 right = st.lowerRight - st.lowerLeft, up = st.upperLeft - st.lowerLeft;
    const float W = float(wall.width), H = float(wall.height);
    const PixelRect& vp = s.viewport;
    f.lowerLeft = st.lowerLeft + right * (float(vp.x) / W) + up * (float(wall.height - (vp.y + vp.height)) / H);
    f.right = right * (float(vp.width) / W);
    f.up = up * (float(vp.height) / H);
    return f;
}

namespace {

std::string format3(Float3 p) {
    char text[96];
    std::snprintf(text, sizeof text, "(%.4g, %.4g, %.4g)", double(p.x), double(p.y), double(p.z));
    return text;
}

// Profile 3d: where a region's frustum coordinates put each projector pixel's ray, as points in
// room coordinates (metres): along its frustum direction from the calibration's eye point, at
// the frustum distance along the frustum's axis. NaN samples stay NaN.
Float3 simulationPoint(const FrustumAxes& axes, Float3 eyepoint, double distance, Float3 uv) {
    if (std::isnan(uv.x) || std::isnan(uv.y) || std::isnan(uv.z)) return uv;
    return eyepoint + axes.direction(uv.x, uv.y) * float(distance);
}

Float3 eyepointOf(const WallConfig& wall) { return wall.warp->eyepoint.value_or(wall.stereo.viewer); }

}  // namespace

double regionTop(const WarpConfig& warp, const MpcdiRegion& region) {
    return warp.regionYFromBottom ? 1.0 - region.y - region.ySize : region.y;
}

std::vector<std::string> checkWarp(const WallConfig& wall) {
    std::vector<std::string> problems;
    if (!wall.warp) return problems;
    const WarpConfig& warp = *wall.warp;
    const std::string at = wall.file.string() + ": [warp]: ";
    MpcdiFile file;
    try {
        file = readMpcdi(warp.mpcdi);
    } catch (const InputError& e) {
        problems.push_back(at + e.what());
        return problems;
    }
    const std::string mpcdiName = warp.mpcdi.filename().string();
    const bool simulation = file.profile == MpcdiProfile::Simulation3d;
    const Float3 eyepoint = eyepointOf(wall);
    for (const MpcdiBuffer& b : file.buffers)
        if (std::none_of(warp.buffers.begin(), warp.buffers.end(), [&](const auto& m) { return m.first == b.id; }))
            problems.push_back(at + "buffer '" + b.id + "' of " + mpcdiName + " drives no screen (map it in 'buffers')");
    for (const auto& [id, screenName] : warp.buffers) {
        const MpcdiBuffer* b = file.buffer(id);
        if (!b) {
            std::string have;
            for (const MpcdiBuffer& o : file.buffers) have += (have.empty() ? "" : ", ") + o.id;
            problems.push_back(at + "buffer '" + id + "' is not in " + mpcdiName + " (it has " + have + ")");
            continue;
        }
        const auto it = std::find_if(wall.screens.begin(), wall.screens.end(), [&](const ScreenConfig& s) { return s.name == screenName; });
        const size_t index = size_t(it - wall.screens.begin());
        const ScreenConfig& screen = *it;
        const std::string where = at + "buffer '" + id + "' (screen '" + screenName + "'): ";
        const int sw = screen.outputWidth > 0 ? screen.outputWidth : screen.viewport.width;
        const int sh = screen.outputHeight > 0 ? screen.outputHeight : screen.viewport.height;
        if (b->xResolution != sw || b->yResolution != sh) {
            problems.push_back(where + std::to_string(b->xResolution) + "x" + std::to_string(b->yResolution) +
                               " pixels, the screen has " + std::to_string(sw) + "x" + std::to_string(sh));
            continue;
        }
        const EyeWindow frame = screenFrame(wall, index);
        const float width = length(frame.right), height = length(frame.up);
        const Float3 ex = frame.right * (1.0f / (width * width)), ey = frame.up * (1.0f / (height * height));
        const Float3 normal = normalize(cross(frame.right, frame.up));
        const float diagonal = std::sqrt(width * width + height * height);
        const float eyeDepth = dot(eyepoint - frame.lowerLeft, normal);
        for (const MpcdiRegion& r : b->regions) {
            const int rw = int(std::lround(r.xSize * b->xResolution)), rh = int(std::lround(r.ySize * b->yResolution));
            if (r.xResolution != rw || r.yResolution != rh) {
                problems.push_back(where + "region '" + r.id + "' has " + std::to_string(r.xResolution) + "x" +
                                   std::to_string(r.yResolution) + " pixels for its " + std::to_string(rw) + "x" +
                                   std::to_string(rh) + " of the buffer");
                continue;
            }
            size_t outside = 0;
            std::string first;
            const FrustumAxes axes = simulation ? frustumAxes(*r.frustum) : FrustumAxes{};
            for (int j = 0; j < r.warp.height; ++j)
                for (int i = 0; i < r.warp.width; ++i) {
                    const Float3 p = r.warp.samples[size_t(j) * size_t(r.warp.width) + size_t(i)];
                    if (std::isnan(p.x) || std::isnan(p.y) || std::isnan(p.z)) continue;
                    float s = 0, t = 0, off = 0;
                    if (simulation) {
                        // Where the pixel's ray from the eye point meets the screen's frame (a
                        // curved screen's chord: the ray passes the surface on its way); behind
                        // the eye point or parallel to the frame: outside.
                        const Float3 d = axes.direction(p.x, p.y);
                        const float den = dot(d, normal), along = den != 0.0f ? -eyeDepth / den : -1.0f;
                        if (along > 0.0f) {
                            const Float3 q = eyepoint + d * along - frame.lowerLeft;
                            s = dot(q, ex);
                            t = dot(q, ey);
                        } else {
                            s = t = std::numeric_limits<float>::infinity();
                        }
                    } else if (warpsToSurface(file.profile)) {
                        const Float3 q = p * float(r.warp.metresPerUnit) - frame.lowerLeft;
                        s = dot(q, ex);
                        t = dot(q, ey);
                        off = std::abs(dot(q, normal));
                    } else {
                        s = p.x;
                        t = p.y;
                    }
                    constexpr float kSlack = 0.02f;
                    if (s < -kSlack || s > 1 + kSlack || t < -kSlack || t > 1 + kSlack || off > diagonal) {
                        if (outside++ == 0) {
                            char pos[96];
                            std::snprintf(pos, sizeof pos, " (%.3g, %.3g of the frame%s)", double(s), double(t),
                                          off > diagonal ? ", far off its plane" : "");
                            first = "sample (" + std::to_string(i) + ", " + std::to_string(j) + ") at " + format3(p) + pos;
                        }
                    }
                }
            if (outside > 0)
                problems.push_back(where + "region '" + r.id + "': " + std::to_string(outside) + " of " +
                                   std::to_string(r.warp.validSamples) + " warp samples lie outside the screen's frame, first " +
                                   first + (warpsToSurface(file.profile) ? "; is the geometric unit right?"
                                            : simulation             ? "; are the eye point and the frustum right?"
                                                                     : ""));
        }
    }
    return problems;
}

std::vector<WallWarp> wallWarps(const WallConfig& wall, const MpcdiFile& file) {
    std::vector<WallWarp> out;
    if (!wall.warp) return out;
    for (const auto& [id, screenName] : wall.warp->buffers) {
        const MpcdiBuffer* b = file.buffer(id);
        const auto it = std::find_if(wall.screens.begin(), wall.screens.end(), [&](const ScreenConfig& s) { return s.name == screenName; });
        if (!b || it == wall.screens.end()) continue;
        WallWarp ww;
        ww.screen = size_t(it - wall.screens.begin());
        const PixelRect& vp = it->viewport;
        // Buffer pixels to wall pixels of the viewport.
        const double sx = double(vp.width) / b->xResolution, sy = double(vp.height) / b->yResolution;
        for (const MpcdiRegion& r : b->regions) {
            ScreenWarp sw;
            const double bx0 = r.x * b->xResolution;
            const double by0 = regionTop(*wall.warp, r) * b->yResolution;
            const double bw = r.xSize * b->xResolution, bh = r.ySize * b->yResolution;
            sw.rect = {vp.x + int(std::lround(bx0 * sx)), vp.y + int(std::lround(by0 * sy)),
                       vp.x + int(std::lround((bx0 + bw) * sx)), vp.y + int(std::lround((by0 + bh) * sy))};
            auto grid = std::make_shared<PixelWarp>();
            grid->width = r.warp.width;
            grid->height = r.warp.height;
            grid->samples.resize(r.warp.samples.size());
            if (file.profile == MpcdiProfile::Simulation3d) {
                grid->kind = PixelWarp::Kind::SurfacePoints;
                const FrustumAxes axes = frustumAxes(*r.frustum);
                const Float3 eyepoint = eyepointOf(wall);
                for (size_t k = 0; k < r.warp.samples.size(); ++k)
                    grid->samples[k] = simulationPoint(axes, eyepoint, wall.warp->frustumDistance, r.warp.samples[k]);
            } else if (warpsToSurface(file.profile)) {
                grid->kind = PixelWarp::Kind::SurfacePoints;
                const float m = float(r.warp.metresPerUnit);
                for (size_t k = 0; k < r.warp.samples.size(); ++k) grid->samples[k] = r.warp.samples[k] * m;
            } else {
                grid->kind = PixelWarp::Kind::ScreenOffsets;
                // The sample's pixel centre and where (u, v) lands on the flat screen, in wall
                // pixels; u from the left, v up from the bottom of the screen.
                const double cw = double(sw.rect.width()) / grid->width, ch = double(sw.rect.height()) / grid->height;
                auto snap = [](double v) { return float(std::round(v * 1024.0) / 1024.0); };
                for (int j = 0; j < grid->height; ++j)
                    for (int i = 0; i < grid->width; ++i) {
                        const size_t k = size_t(j) * size_t(grid->width) + size_t(i);
                        const Float3 uv = r.warp.samples[k];
                        if (std::isnan(uv.x) || std::isnan(uv.y) || std::isnan(uv.z)) {
                            grid->samples[k] = uv;
                            continue;
                        }
                        const double cx = sw.rect.x0 + (i + 0.5) * cw, cy = sw.rect.y0 + (j + 0.5) * ch;
                        const double px = vp.x + double(uv.x) * vp.width, py = vp.y + (1.0 - double(uv.y)) * vp.height;
                        grid->samples[k] = {snap(px - cx), snap(py - cy), 0.0f};
                    }
            }
            sw.warp = std::move(grid);
            ww.regions.push_back(std::move(sw));
        }
        out.push_back(std::move(ww));
    }
    return out;
}

}  // namespace rtwall
