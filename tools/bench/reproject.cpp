// rtwall bench reproject: how good re-projected frames look (issue 27). A head steps in front of
// a tracked 3.2 m x 2.4 m wall (mono, off-axis eye cameras as the wall session makes them) at
// each speed; a cluster renders at each rate, every frame for the head's pose at its start and
// complete one period later; a display at display_hz shows at each refresh the newest complete
// frame (one to two periods old) warped to the head's true pose at that moment, with the frame
// before it as the older view for holes, or the same frame as it is (no re-projection). Each
// shown image is scored against a true render of that pose: PSNR and mean FLIP, medians and the
// worst 5 %, over the whole image and its edges, and the share of holes. Guard bands render each
// frame wider and higher than the screen; the failure cases (reproject_cases.cpp) write an image
// each. The renders are the engine's own (renderFrameWithDepth), no cluster: the model above
// stands for its timing.
#include "bench.h"
#include "bench_util.h"
#include "reproject_quality.h"

#include <cmath>
#include <cstdio>
#include <string>

namespace rtwall::bench {

namespace rq = reproject;

toml::table reprojectionFailureCases(const ReprojectOptions& o);  // reproject_cases.cpp

namespace {

// A JSON number for NaN (a region with no pixels): JSON has no NaN, so -1.
double finite(double v) { return std::isfinite(v) ? v : -1.0; }

toml::table spread(const std::vector<double>& v, bool higherIsBetter) {
    return toml::table{{"median", finite(median(v))}, {"p95", finite(rq::worst5(v, higherIsBetter))}};
}

template <class Field> std::vector<double> field(const std::vector<rq::Score>& scores, Field f) {
    std::vector<double> out;
    for (const rq::Score& s : scores) out.push_back(s.*f);
    return out;
}

toml::table row(const std::string& scene, double speed, const rq::Track& track, const rq::Series& s, bool warped,
                const ReprojectOptions& o) {
    const std::vector<rq::Score>& scores = warped ? s.warped : s.stale;
    std::vector<double> ageMs;
    for (double a : s.ageSeconds) ageMs.push_back(1e3 * a);
    return toml::table{{"scene", scene},
                       {"speed_m_s", speed},
                       {"render_fps", track.renderFps},
                       {"display_hz", o.displayHz},
                       {"width", o.width},
                       {"height", o.height},
                       {"warped", warped},
                       {"guard_band", track.guardBand},
                       {"rendered_pixels", s.renderedPixels},
                       {"frames", int64_t(scores.size())},
                       {"age_ms", toml::table{{"median", median(ageMs)}, {"max", *std::max_element(ageMs.begin(), ageMs.end())}}},
                       {"psnr_db", spread(field(scores, &rq::Score::psnrDb), true)},
                       {"flip", spread(field(scores, &rq::Score::flip), false)},
                       {"holes", warped ? spread(s.holes, false) : toml::table{{"median", 0.0}, {"p95", 0.0}}},
                       {"edge_psnr_db", spread(field(scores, &rq::Score::edgePsnrDb), true)},
                       {"edge_flip", spread(field(scores, &rq::Score::edgeFlip), false)}};
}

void printRow(std::FILE* text, const toml::table& r) {
    if (!text) return;
    auto num = [&r](const char* key, const char* sub) { return r[key][sub].value_or(0.0); };
    std::fprintf(text, "%-5s %4.2f m/s %2.0f fps %-6s guard %4.1f%%: PSNR %5.1f dB (worst 5%% %5.1f), FLIP %.3f (%.3f), holes %.2f%%, "
                       "edges PSNR %5.1f FLIP %.3f\n",
                 r["scene"].value_or(""), r["speed_m_s"].value_or(0.0), r["render_fps"].value_or(0.0),
                 r["warped"].value_or(false) ? "warped" : "stale", 100 * r["guard_band"].value_or(0.0), num("psnr_db", "median"),
                 num("psnr_db", "p95"), num("flip", "median"), num("flip", "p95"), 100 * num("holes", "median"),
                 num("edge_psnr_db", "median"), num("edge_flip", "median"));
    std::fflush(text);
}

}  // namespace

toml::table reprojection(const ReprojectOptions& o) {
    toml::table out{{"benchmark", "reproject"},
                    {"width", o.width},
                    {"height", o.height},
                    {"display_hz", o.displayHz},
                    {"seconds", o.seconds},
                    {"seed", int64_t(o.seed)},
                    {"flip", "mean LDR-FLIP, 67 pixels per degree"},
                    {"p95", "the value 95 % of displayed frames are at least as good as (PSNR: 5th percentile)"},
                    {"edge", "pixels within 5 % of the width of the left or right edge or of the height of the top or bottom"},
                    {"model", "frame k starts at phase + k/render_fps for the head's pose then, is complete 1/render_fps later; "
                              "each refresh shows the newest complete frame (one to two periods old), frame k-1 fills holes"}};
    std::vector<rq::Track> tracks;
    for (double fps : o.renderFps) {
        tracks.push_back({fps, 0.0});
        for (double g : o.guardBands)
            if (g > 0) tracks.push_back({fps, g});
    }
    rq::MeasureOptions m;
    m.width = o.width;
    m.height = o.height;
    m.displayHz = o.displayHz;
    m.seconds = o.seconds;
    m.seed = o.seed;
    toml::array rows;
    for (const std::string& name : o.scenes) {
        rq::BenchScene s = rq::benchScene(name, o.demo, o.dir, o.plantTriangles);
        s.desc.settings.threads = 0;
        const Scene scene(s.desc);
        for (double speed : o.speeds) {
            const std::vector<rq::Series> series = rq::measure(scene, s.desc.settings, s.rig, speed, tracks, m);
            for (size_t j = 0; j < tracks.size(); ++j) {
                rows.push_back(row(name, speed, tracks[j], series[j], true, o));
                printRow(o.text, *rows.back().as_table());
                if (tracks[j].guardBand > 0) continue;
                rows.push_back(row(name, speed, tracks[j], series[j], false, o));
                printRow(o.text, *rows.back().as_table());
            }
        }
    }
    out.insert("rows", rows);
    if (o.failureCases) out.insert("failure_cases", reprojectionFailureCases(o));
    return out;
}

}  // namespace rtwall::bench
