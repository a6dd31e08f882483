// rtwall bench scene SCENE: what loading and rendering a big scene costs. Load from the mesh
// files (parse), from the caches, the BVH build, resident bytes, and frame times at 1600x1200
// with primary rays and shadows, for the scene's [bvh] primitives and the other choice; with
// --sweep, the same for every BVH quality and compact mode.
#include "bench.h"
#include "bench_util.h"
#include "progress.h"

#include <rtwall/engine.h>

#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <set>
#include <thread>

#include <time.h>

namespace rtwall::bench {

namespace {

// CPU seconds of the whole process (all threads): on a shared machine, wall time alone says
// little about the work done.
double cpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// VmRSS / VmHWM of this process in bytes.
int64_t procStatus(const char* key) {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.starts_with(key)) return std::stoll(line.substr(std::string(key).size() + 1)) * 1024;
    return -1;
}

const char* primitivesName(BvhSettings::Primitives p) {
    return p == BvhSettings::Primitives::Triangles ? "triangles" : "auto";
}

const char* qualityName(BvhSettings::Quality q) {
    return q == BvhSettings::Quality::Low ? "low" : q == BvhSettings::Quality::High ? "high" : "medium";
}


struct Triangles {
    int64_t unique = 0, instanced = 0;
};

// 1. Parse every mesh file (no caches), 2. make sure caches exist, 3. load from them; the
// figures go into `out`.
SceneDesc loadTimed(const SceneOptions& o, toml::table& out, Triangles& tris) {
    const std::filesystem::path path(o.scene);
    if (!o.skipParse) {
        SceneLoadStats parse;
        SceneLoadOptions lo;
        lo.cache = false;
        lo.stats = &parse;
        ProgressBar bar("import", 1, "");
        lo.progress = bar.fn();
        const double cpu0 = cpuSeconds();
        const double total = secondsOf([&] { (void)loadSceneFile(path, lo); });
        out.insert("parse_load_s", total);
        out.insert("parse_load_cpu_s", cpuSeconds() - cpu0);
        out.insert("parse_import_s", parse.importSeconds);
    }
    {
        SceneLoadStats fill;
        SceneLoadOptions lo;
        lo.cache = true;
        lo.stats = &fill;
        const double total = secondsOf([&] { (void)loadSceneFile(path, lo); });
        out.insert("cache_fill_s", total);
        out.insert("caches_written", int64_t(fill.cacheWritten));
    }
    SceneLoadStats cached;
    SceneLoadOptions lo;
    lo.cache = true;
    lo.stats = &cached;
    SceneDesc desc;
    const double cpuLoad0 = cpuSeconds();
    const double cacheLoad = secondsOf([&] { desc = loadSceneFile(path, lo); });
    out.insert("cache_load_cpu_s", cpuSeconds() - cpuLoad0);
    out.insert("cache_load_s", cacheLoad);
    out.insert("cache_read_s", cached.cacheSeconds);
    out.insert("cache_hits", int64_t(cached.cacheHits));

    std::set<const TriangleMesh*> seen;
    for (const MeshDesc& m : desc.meshes)
        if (seen.insert(m.mesh.get()).second) tris.unique += int64_t(m.mesh->triangleCount());
    for (const InstanceDesc& in : desc.instances) tris.instanced += int64_t(desc.meshes[in.mesh].mesh->triangleCount());
    out.insert("unique_triangles", tris.unique);
    out.insert("instanced_triangles", tris.instanced);
    out.insert("instances", int64_t(desc.instances.size()));
    out.insert("meshes", int64_t(desc.meshes.size()));
    return desc;
}

// The BVH settings measured: the scene's, the other primitives choice, then the sweep's.
std::vector<BvhSettings> bvhSettings(const SceneOptions& o, const BvhSettings& bvh, size_t& firstSweepRow) {
    std::vector<BvhSettings> settings{bvh};
    // Row 1 (key "other_primitives"): the scene's settings with the other primitives choice.
    if (o.otherPrimitives) {
        BvhSettings other = bvh;
        other.primitives = other.primitives == BvhSettings::Primitives::Auto ? BvhSettings::Primitives::Triangles
                                                                            : BvhSettings::Primitives::Auto;
        settings.push_back(other);
    }
    firstSweepRow = settings.size();
    if (o.sweep)
        for (auto q : {BvhSettings::Quality::Low, BvhSettings::Quality::Medium, BvhSettings::Quality::High})
            for (bool compact : {false, true}) settings.push_back({q, compact, bvh.robust, bvh.primitives});
    return settings;
}

// Build the BVH of `desc` as it is and render o.frames frames: one row.
toml::table measure(const SceneDesc& desc, const CameraDesc& camera, const RenderSettings& s, const SceneOptions& o,
                    const Triangles& tris) {
    const int64_t unique = tris.unique, instanced = tris.instanced;
    std::unique_ptr<Scene> scene;
    ProgressBar bar("bvh build", double(unique) * 1e-6, "Mtri");
    const double cpu0 = cpuSeconds();
    const double build = secondsOf([&] { scene = std::make_unique<Scene>(desc, bar.fn()); });
    const double buildCpu = cpuSeconds() - cpu0;
    const Camera c(camera, s.width, s.height);
    std::vector<double> frames;
    TileStats stats;
    renderFrame(*scene, c, s, 0, &stats);  // warm-up
    const double cpu1 = cpuSeconds();
    for (int f = 0; f < o.frames; ++f) frames.push_back(secondsOf([&] { renderFrame(*scene, c, s, 0); }));
    const double frameCpu = (cpuSeconds() - cpu1) / o.frames;
    const double geometry = double(scene->geometryBytes()), embree = double(scene->embreeBytes());
    size_t mapped = 0;
    std::set<const TriangleMesh*> counted;
    for (const MeshDesc& m : desc.meshes)
        if (counted.insert(m.mesh.get()).second) mapped += m.mesh->mappedBytes();
    const Scene::PrimitiveStats ps = scene->primitiveStats();
    const toml::table row{{"quality", qualityName(desc.bvh.quality)},
                         {"primitives", primitivesName(desc.bvh.primitives)},
                         // Triangle pairs (2k, 2k+1), those sharing an edge, the quads Embree
                         // got (read in place from the meshes' index arrays or from a buffer
                         // made for it, quad_index_bytes) and the triangles it got as such.
                         {"triangle_pairs", int64_t(ps.pairs)},
                         {"pairs_sharing_edge", int64_t(ps.pairsSharingEdge)},
                         {"quads", int64_t(ps.quads)},
                         {"quads_in_place", int64_t(ps.quadsInPlace)},
                         {"separate_triangles", int64_t(ps.separateTriangles)},
                         {"quad_index_bytes", int64_t(ps.quadIndexBytes)},
                         {"meshes_as_quads", int64_t(ps.meshesAsQuads)},
                         {"meshes_as_triangles", int64_t(ps.meshesAsTriangles)},
                         {"compact", desc.bvh.compact},
                         {"robust", desc.bvh.robust},
                         {"bvh_build_s", build},
                         {"bvh_build_cpu_s", buildCpu},
                         {"geometry_bytes", int64_t(geometry)},
                         {"embree_bytes", int64_t(embree)},
                         {"embree_top_level_bytes", int64_t(scene->embreeTopLevelBytes())},
                         {"embree_bytes_per_instance_top_level", double(scene->embreeTopLevelBytes()) / double(std::max<size_t>(1, desc.instances.size()))},
                         {"rss_bytes_per_instanced_triangle", double(procStatus("VmRSS:")) / double(std::max<int64_t>(1, instanced))},
                         {"bytes_per_unique_triangle", (geometry + embree) / double(std::max<int64_t>(1, unique))},
                         {"rss_bytes", procStatus("VmRSS:")},
                         {"rss_bytes_per_unique_triangle", double(procStatus("VmRSS:")) / double(std::max<int64_t>(1, unique))},
                         // Where the resident bytes are: heap and Embree (anonymous), mapped
                         // mesh caches (file), VTK import results (shared memory).
                         {"rss_anon_bytes", procStatus("RssAnon:")},
                         {"rss_file_bytes", procStatus("RssFile:")},
                         {"rss_shmem_bytes", procStatus("RssShmem:")},
                         {"mapped_geometry_bytes", int64_t(mapped)},
                         // Embree 3 builds spatial splits only for quality high on a scene
                         // that is neither robust nor compact; otherwise high is medium.
                         {"spatial_splits", desc.bvh.quality == BvhSettings::Quality::High && !desc.bvh.robust && !desc.bvh.compact},
                         {"frame_s", median(frames)},
                         {"frame_cpu_s", frameCpu},
                         {"rays_per_frame", int64_t(stats.rays + stats.shadowRays)}};

    if (o.text)
        std::fprintf(o.text, "bvh %-9s %-6s compact=%d: build %.2f s, %.1f B/unique tri (geometry+Embree), rss %.2f GB, frame %.3f s\n",
                    primitivesName(desc.bvh.primitives), qualityName(desc.bvh.quality), int(desc.bvh.compact), build, (geometry + embree) / double(std::max<int64_t>(1, unique)),
                    double(procStatus("VmRSS:")) * 1e-9, median(frames));
    return row;
}

}  // namespace

toml::table scene(const SceneOptions& o) {
    toml::table out{{"benchmark", "scene"}, {"scene", o.scene}};
    Triangles tris;
    SceneDesc desc = loadTimed(o, out, tris);
    const CameraDesc* cam = o.camera.empty() ? &desc.cameras.front() : desc.findCamera(o.camera);
    if (!cam) throw InputError(o.scene + ": no camera named '" + o.camera + "'");
    const CameraDesc camera = *cam;
    RenderSettings s = desc.settings;
    s.width = o.width;
    s.height = o.height;
    s.threads = o.threads;
    s.shading = ShadingMode::Full;
    s.shadows = true;
    s.maxDepth = 1;  // primary rays plus shadow rays
    s.supersample = 1;

    if (o.robust != "scene") desc.bvh.robust = o.robust == "on";
    size_t firstSweepRow = 0;
    const std::vector<BvhSettings> settings = bvhSettings(o, desc.bvh, firstSweepRow);
    toml::array rows;
    for (size_t i = 0; i < settings.size(); ++i) {
        desc.bvh = settings[i];
        toml::table row = measure(desc, camera, s, o, tris);
        if (i == 0) out.insert("default", row);
        else if (i < firstSweepRow) out.insert("other_primitives", row);
        else rows.push_back(row);
    }
    if (o.sweep) out.insert("sweep", rows);
    out.insert("peak_rss_bytes", procStatus("VmHWM:"));
    out.insert("width", o.width);
    out.insert("height", o.height);
    out.insert("threads", o.threads > 0 ? o.threads : int(std::max(1u, std::thread::hardware_concurrency())));
    if (o.text) printToml(o.text, out);
    return out;
}

}  // namespace rtwall::bench
