// rtwall bench tessellation: what the STEP tessellation tolerance buys and costs. A STEP assembly
// of curved parts (`rtwall gen step-curved`: fillets, spheres, tori) is imported at every pair of
// linear and angular deflection; each row gives the unique and instanced triangles, the bytes of
// the mesh buffers and of Embree's BVHs, the import time (OpenCASCADE's transfer plus
// BRepMesh, median of --runs cold imports, no assembly cache), and the image error against the
// same view of a much finer tessellation (the reference), rendered with the same camera and
// samples, so that the only difference is the geometry.
#include "bench.h"
#include "bench_util.h"
#include "generators.h"

#include <rtwall/engine.h>
#include <rtwall/tune.h>

#include <toml++/toml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <vector>

namespace rtwall::bench {

namespace {

struct Loaded {
    SceneDesc desc;
    double importSeconds = 0;  // median
    int64_t unique = 0, instanced = 0, geometryBytes = 0;
};

Loaded load(const std::filesystem::path& file, double linear, double angular, int runs) {
    SceneLoadOptions lo;
    lo.linearDeflection = linear;
    lo.angularDeflection = angular;
    lo.cache = false;  // every run imports through OpenCASCADE
    Loaded out;
    std::vector<double> t;
    for (int r = 0; r < runs; ++r) t.push_back(secondsOf([&] { out.desc = loadScene(file.string(), lo); }));
    out.importSeconds = median(t);
    std::set<const TriangleMesh*> seen;
    for (const MeshDesc& m : out.desc.meshes)
        if (seen.insert(m.mesh.get()).second) {
            out.unique += int64_t(m.mesh->triangleCount());
            out.geometryBytes += int64_t(m.mesh->residentBytes());
        }
    for (const InstanceDesc& in : out.desc.instances) out.instanced += int64_t(out.desc.meshes[in.mesh].mesh->triangleCount());
    return out;
}

struct Rendered {
    Image image;
    double buildSeconds = 0, frameSeconds = 0;
    int64_t embreeBytes = 0;
};

Rendered render(const SceneDesc& desc, const CameraDesc& camera, const RenderSettings& s) {
    Rendered out;
    std::unique_ptr<Scene> scene;
    out.buildSeconds = secondsOf([&] { scene = std::make_unique<Scene>(desc); });
    out.embreeBytes = int64_t(scene->embreeBytes());
    const Camera cam(camera, s.width, s.height);
    out.frameSeconds = secondsOf([&] { out.image = renderFrame(*scene, cam, s, 1); });
    return out;
}

}  // namespace

toml::table tessellation(const TessellationOptions& o) {
    gen::GenOptions g;
    g.out = o.dir;
    g.instances = o.instances;
    gen::genStepCurved(g);
    const std::filesystem::path file = std::filesystem::path(o.dir) / "assembly.step";

    // The reference fixes the camera (the view that frames the finest model) and the settings.
    const Loaded ref = load(file, o.referenceLinear, o.referenceAngular, 1);
    const CameraDesc camera = ref.desc.cameras.front();
    RenderSettings s = ref.desc.settings;
    s.width = o.width;
    s.height = o.height;
    s.threads = o.threads;
    s.supersample = o.supersample;
    const Rendered refImage = render(ref.desc, camera, s);
    if (o.text)
        std::fprintf(o.text, "reference: linear %g, angular %g rad: %lld unique triangles, import %.2f s\n", o.referenceLinear,
                     o.referenceAngular, (long long)ref.unique, ref.importSeconds);

    toml::array rows;
    for (double linear : o.linear)
        for (double angular : o.angular) {
            const Loaded l = load(file, linear, angular, o.runs);
            const Rendered r = render(l.desc, camera, s);
            const ImageError e = compareImages(r.image, refImage.image);
            rows.push_back(toml::table{{"linear_deflection", linear},
                                       {"angular_deflection", angular},
                                       {"unique_triangles", l.unique},
                                       {"instanced_triangles", l.instanced},
                                       {"geometry_bytes", l.geometryBytes},
                                       {"embree_bytes", r.embreeBytes},
                                       {"import_s", l.importSeconds},
                                       {"bvh_build_s", r.buildSeconds},
                                       {"frame_s", r.frameSeconds},
                                       {"rmse", e.rmse},
                                       {"psnr_db", e.psnrDb},
                                       {"ssim", e.ssim},
                                       {"flip", e.flip},
                                       {"max_error", e.maxError}});
            if (o.text)
                std::fprintf(o.text,
                             "linear %-6g angular %-5g: %8lld unique triangles, %7.2f MB mesh + %7.2f MB BVH, import %.3f s, "
                             "RMSE %.3f (PSNR %.1f dB, FLIP %.4f)\n",
                             linear, angular, (long long)l.unique, double(l.geometryBytes) * 1e-6, double(r.embreeBytes) * 1e-6,
                             l.importSeconds, e.rmse, e.psnrDb, e.flip);
        }

    return toml::table{{"benchmark", "tessellation"},
                       {"file", file.string()},
                       {"instances", int64_t(ref.desc.instances.size())},
                       {"meshes", int64_t(ref.desc.meshes.size())},
                       {"width", o.width},
                       {"height", o.height},
                       {"supersample", o.supersample},
                       {"runs", o.runs},
                       {"reference", toml::table{{"linear_deflection", o.referenceLinear},
                                                 {"angular_deflection", o.referenceAngular},
                                                 {"unique_triangles", ref.unique},
                                                 {"geometry_bytes", ref.geometryBytes},
                                                 {"embree_bytes", refImage.embreeBytes},
                                                 {"import_s", ref.importSeconds},
                                                 {"frame_s", refImage.frameSeconds}}},
                       {"rows", rows}};
}

}  // namespace rtwall::bench
