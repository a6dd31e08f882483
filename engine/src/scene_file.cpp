// TOML scene files (format documented in configs/README.md).
#include "vec.h"

#include <rtwall/engine.h>
#include <rtwall/toml_reader.h>

#include <toml++/toml.h>

#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

namespace rtwall {

namespace {

using toml_reader::Reader;
using toml_reader::forEachTable;
using toml_reader::subTable;
using toml_reader::where;

void readSettings(Reader& top, const std::filesystem::path& file, RenderSettings& s) {
    if (const toml::table* t = subTable(top, "image")) {
        Reader r(file, *t, "[image]: ");
        s.width = r.integer("width", s.width, 1, 16384);
        s.height = r.integer("height", s.height, 1, 16384);
        s.tileSize = r.integer("tile", s.tileSize, 1, 1024);
        r.finish();
    }
    if (const toml::table* t = subTable(top, "render")) {
        Reader r(file, *t, "[render]: ");
        s.kernel = r.choice("kernel", "packet", {"packet", "single"}) == "single" ? KernelType::Single
                                                                                   : KernelType::Packet;
        s.shading = r.choice("shading", "full", {"full", "eyelight"}) == "eyelight" ? ShadingMode::EyeLight
                                                                                     : ShadingMode::Full;
        s.maxDepth = r.integer("max_depth", s.maxDepth, 1, 64);
        s.supersample = r.integer("supersample", s.supersample, 1, 16);
        s.shadows = r.boolean("shadows", s.shadows);
        s.background = r.vec3("background", s.background);
        s.ambient = r.vec3("ambient", s.ambient);
        s.threads = r.integer("threads", s.threads, 0, 1024);
        r.finish();
    }
}

std::shared_ptr<const TriangleMesh> makeShape(Reader& r, const std::string& shape) {
    if (shape == "sphere") {
        const int rings = r.integer("rings", 32, 2, 4096), segments = r.integer("segments", 64, 3, 8192);
        return std::make_shared<const TriangleMesh>(makeSphere(rings, segments));
    }
    if (shape == "box") return std::make_shared<const TriangleMesh>(makeBox());
    if (shape == "quad") return std::make_shared<const TriangleMesh>(makeQuad());
    // torus_knot
    const int p = r.integer("p", 2, 1, 64), q = r.integer("q", 3, 1, 64);
    const int segments = r.integer("segments", 256, 3, 1 << 20), sides = r.integer("sides", 16, 3, 4096);
    const float radius = float(r.number("radius", 0.25, 1e-6, 1e6));
    if (int64_t(segments) * sides > (int64_t(1) << 26))
        r.fail(r.find("segments"), "torus_knot: segments x sides must stay below 2^26 vertices");
    return std::make_shared<const TriangleMesh>(makeTorusKnot(p, q, segments, sides, radius));
}

Transform readTransform(Reader& r) {
    // Applied in this order: scale, rotate (x, then y, then z, in degrees), translate.
    Transform t;
    if (r.has("scale")) {
        const toml::node* n = r.find("scale");
        if (n->is_number()) {
            const double s = r.number("scale", 1.0, 1e-12, 1e12);
            t = Transform::scale(s, s, s);
        } else {
            const Float3 s = r.vec3("scale", {1, 1, 1});
            if (s.x == 0 || s.y == 0 || s.z == 0) r.fail(n, "key 'scale': factors must not be zero");
            t = Transform::scale(s.x, s.y, s.z);
        }
    }
    const Float3 rot = r.vec3("rotate", {0, 0, 0});
    t = Transform::rotateDegrees(1, 0, 0, rot.x) * t;
    t = Transform::rotateDegrees(0, 1, 0, rot.y) * t;
    t = Transform::rotateDegrees(0, 0, 1, rot.z) * t;
    const Float3 tr = r.vec3("translate", {0, 0, 0});
    return Transform::translate(tr.x, tr.y, tr.z) * t;
}

CameraDesc framingCamera(const Bounds3& b) {
    CameraDesc c;
    c.name = "default";
    if (b.empty()) return c;
    const Float3 center = (b.lo + b.hi) * 0.5f;
    const float radius = std::max(1e-6f, 0.5f * length(b.hi - b.lo));
    c.fovY = 40.0f;
    // Far enough that the bounding sphere fits the vertical field of view, seen from the front-right, slightly above.
    const float dist = radius / std::sin(float(c.fovY * std::numbers::pi / 360.0)) * 1.05f;
    c.position = center + normalize(Float3{0.45f, 0.35f, 1.0f}) * dist;
    c.lookAt = center;
    c.up = {0, 1, 0};
    return c;
}

}  // namespace

SceneDesc loadSceneFile(const std::filesystem::path& file) {
    const toml::table root = toml_reader::parseFile(file);

    SceneDesc scene;
    scene.sourceFile = file;
    const std::filesystem::path dir = file.parent_path();
    Reader top(file, root, "");
    readSettings(top, file, scene.settings);

    std::map<std::string, uint32_t> meshIndex, materialIndex;
    std::map<std::filesystem::path, std::shared_ptr<const TriangleMesh>> loadedFiles;  // one copy per file
    forEachTable(top, file, "mesh", [&](Reader& r, const toml::table&) {
        MeshDesc md;
        md.name = r.string("name", "", true);
        if (meshIndex.count(md.name)) r.fail(r.find("name"), "mesh name '" + md.name + "' is used twice");
        const bool hasFile = r.has("file"), hasShape = r.has("shape");
        if (hasFile == hasShape) r.fail(nullptr, "give exactly one of 'file' and 'shape'");
        if (hasFile) {
            const std::filesystem::path path = dir / r.string("file", "");
            md.source = path.string();
            std::error_code ec;
            const auto key = std::filesystem::weakly_canonical(path, ec);
            auto& slot = loadedFiles[ec ? path : key];
            if (!slot) {
                try {
                    slot = std::make_shared<const TriangleMesh>(loadMesh(path));
                } catch (const InputError& e) {
                    r.fail(r.find("file"), std::string("mesh '") + md.name + "': " + e.what());
                }
            }
            md.mesh = slot;
        } else {
            const std::string shape = r.choice("shape", "", {"sphere", "box", "quad", "torus_knot"});
            md.source = "shape:" + shape;
            try {
                md.mesh = makeShape(r, shape);
            } catch (const std::invalid_argument& e) {
                r.fail(r.find("shape"), std::string("shape '") + shape + "': " + e.what());
            } catch (const std::bad_alloc&) {
                r.fail(r.find("shape"), std::string("shape '") + shape + "': too large to fit in memory");
            }
        }
        meshIndex[md.name] = uint32_t(scene.meshes.size());
        scene.meshes.push_back(std::move(md));
    });

    forEachTable(top, file, "material", [&](Reader& r, const toml::table&) {
        Material m;
        m.name = r.string("name", "", true);
        if (materialIndex.count(m.name)) r.fail(r.find("name"), "material name '" + m.name + "' is used twice");
        const std::string type = r.choice("type", "lambert", {"lambert", "phong", "mirror", "glass"});
        m.type = type == "phong"    ? MaterialType::Phong
                 : type == "mirror" ? MaterialType::Mirror
                 : type == "glass"  ? MaterialType::Glass
                                    : MaterialType::Lambert;
        m.color = r.vec3("color", m.type == MaterialType::Lambert || m.type == MaterialType::Phong
                                      ? Color{0.8f, 0.8f, 0.8f}
                                      : Color{1, 1, 1});
        if (m.type == MaterialType::Phong) {
            m.specular = r.vec3("specular", {0.5f, 0.5f, 0.5f});
            m.shininess = float(r.number("shininess", m.shininess, 1.0, 1e5));
        }
        if (m.type == MaterialType::Glass) m.ior = float(r.number("ior", m.ior, 1.0, 4.0));
        if (maxComponent(m.color) > 1.0f || std::min({m.color.x, m.color.y, m.color.z}) < 0.0f)
            r.fail(r.find("color"), "key 'color': components must lie in [0, 1] (a surface cannot reflect more than it receives)");
        materialIndex[m.name] = uint32_t(scene.materials.size());
        scene.materials.push_back(m);
    });

    forEachTable(top, file, "instance", [&](Reader& r, const toml::table&) {
        InstanceDesc in;
        const std::string mesh = r.string("mesh", "", true);
        auto mi = meshIndex.find(mesh);
        if (mi == meshIndex.end()) r.fail(r.find("mesh"), "key 'mesh': no [[mesh]] is named '" + mesh + "'");
        in.mesh = mi->second;
        const std::string material = r.string("material", "");
        if (material.empty()) {
            if (!materialIndex.count("")) {
                Material def;
                def.name = "";
                materialIndex[""] = uint32_t(scene.materials.size());
                scene.materials.push_back(def);
            }
            in.material = materialIndex[""];
        } else {
            auto it = materialIndex.find(material);
            if (it == materialIndex.end())
                r.fail(r.find("material"), "key 'material': no [[material]] is named '" + material + "'");
            in.material = it->second;
        }
        in.transform = readTransform(r);
        scene.instances.push_back(in);
    });

    forEachTable(top, file, "light", [&](Reader& r, const toml::table&) {
        Light l;
        l.type = r.choice("type", "point", {"point", "directional"}) == "directional" ? LightType::Directional
                                                                                     : LightType::Point;
        if (l.type == LightType::Point) l.position = r.vec3("position", {}, true);
        else {
            l.direction = r.vec3("direction", {}, true);
            if (dot(l.direction, l.direction) == 0.0f) r.fail(r.find("direction"), "key 'direction' must not be zero");
        }
        l.color = r.vec3("color", l.color);
        l.intensity = float(r.number("intensity", 1.0, 0.0, 1e12));
        scene.lights.push_back(l);
    });

    forEachTable(top, file, "camera", [&](Reader& r, const toml::table&) {
        CameraDesc c;
        c.name = r.string("name", "camera" + std::to_string(scene.cameras.size() + 1));
        if (scene.findCamera(c.name)) r.fail(r.find("name"), "camera name '" + c.name + "' is used twice");
        c.position = r.vec3("position", {}, true);
        c.lookAt = r.vec3("look_at", {}, true);
        c.up = r.vec3("up", c.up);
        c.fovY = float(r.number("fov", c.fovY, 0.01, 179.0));
        if (length(c.lookAt - c.position) == 0.0f) r.fail(r.find("look_at"), "camera looks at its own position");
        if (length(cross(c.lookAt - c.position, c.up)) == 0.0f)
            r.fail(r.find("up"), "key 'up' is parallel to the viewing direction");
        scene.cameras.push_back(c);
    });
    top.finish();

    if (scene.cameras.empty()) scene.cameras.push_back(framingCamera(scene.worldBounds()));
    return scene;
}

SceneDesc sceneFromMeshFile(const std::filesystem::path& file) {
    SceneDesc scene;
    scene.sourceFile = file;
    MeshDesc md;
    md.name = file.stem().string();
    md.source = file.string();
    md.mesh = std::make_shared<const TriangleMesh>(loadMesh(file));
    scene.meshes.push_back(md);
    Material m;
    m.name = "default";
    m.type = MaterialType::Phong;
    m.color = {0.7f, 0.7f, 0.72f};
    m.specular = {0.2f, 0.2f, 0.2f};
    scene.materials.push_back(m);
    scene.instances.push_back(InstanceDesc{});
    scene.cameras.push_back(framingCamera(scene.worldBounds()));
    // A head light from above the camera's right shoulder, plus a soft ambient term so nothing is pitch black.
    const CameraDesc& c = scene.cameras.front();
    Light key;
    key.type = LightType::Directional;
    key.direction = normalize((c.lookAt - c.position) + Float3{-0.3f, -0.5f, 0.0f} * length(c.lookAt - c.position));
    key.intensity = 2.5f;
    scene.lights.push_back(key);
    scene.settings.ambient = {0.15f, 0.15f, 0.15f};
    return scene;
}

}  // namespace rtwall
