// Session files (docs/web-console.md, "Session files"): the operator's state as TOML, written
// by the console's "save", read by its "restore" and by `rtwall run --session FILE`. Positions
// are the scene file's coordinates (the rebased origin added back, printed in double with 17
// digits), so a file read back gives the same floats, bit for bit.
#include <rtwall/toml_reader.h>
#include <rtwall/wall.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace rtwall {

namespace {

std::string triple(double x, double y, double z) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "[%.17g, %.17g, %.17g]", x, y, z);
    return buf;
}

std::string world(Float3 p, const std::array<double, 3>& o) {
    return triple(double(p.x) + o[0], double(p.y) + o[1], double(p.z) + o[2]);
}

// TOML strings and arrays of them as toml++ writes them (quotes and escapes its own).
std::string quoted(const std::string& s) {
    std::ostringstream os;
    os << toml::value<std::string>(s);
    return os.str();
}

std::string strings(const std::vector<std::string>& v) {
    toml::array a;
    for (const std::string& e : v) a.push_back(e);
    std::ostringstream os;
    os << a;
    return os.str();
}

void writeCamera(std::ostringstream& os, const CameraDesc& c, const std::array<double, 3>& o) {
    char buf[160];
    os << "position = " << world(c.position, o) << "\nlook_at = " << world(c.lookAt, o);
    std::snprintf(buf, sizeof buf, "\nup = [%.9g, %.9g, %.9g]\nfov = %.9g\n", double(c.up.x), double(c.up.y), double(c.up.z),
                  double(c.fovY));
    os << buf;
}

}  // namespace

std::string writeSessionState(const SessionState& st, const SceneDesc& scene) {
    const std::array<double, 3>& o = scene.origin;
    std::ostringstream os;
    os << "# An rtwall session (the operator console's \"save\"): rtwall run --session FILE brings it back.\n"
       << "# Positions in the scene file's coordinates.\n\n[camera]\n";
    writeCamera(os, st.camera, o);
    for (const Bookmark& b : st.bookmarks) {
        os << "\n[[bookmark]]\nname = " << quoted(b.name) << "\n";
        writeCamera(os, b.camera, o);
    }
    if (!st.parts.empty()) {
        os << "\n[parts]\n";
        if (!st.parts.hide.empty()) os << "hide = " << strings(st.parts.hide) << "\n";
        if (!st.parts.isolate.empty()) os << "isolate = " << strings(st.parts.isolate) << "\n";
        if (!st.parts.highlight.empty()) os << "highlight = " << strings(st.parts.highlight) << "\n";
    }
    char buf[160];
    for (size_t i = 0; i < st.sections.size(); ++i) {
        const SectionPlane& p = st.sections[i];
        if (p == SectionPlane{}) continue;
        os << "\n[[section]]\nslot = " << i << "\nenabled = " << (p.enabled ? "true" : "false") << "\npoint = " << world(p.point, o);
        std::snprintf(buf, sizeof buf, "\nnormal = [%.9g, %.9g, %.9g]\ncap_color = [%.9g, %.9g, %.9g]\ncaps = %s\n",
                      double(p.normal.x), double(p.normal.y), double(p.normal.z), double(p.capColor.x), double(p.capColor.y),
                      double(p.capColor.z), p.caps ? "true" : "false");
        os << buf;
    }
    for (const auto& [i, t] : st.moved) {
        os << "\n[[moved]]\ninstance = " << i << "\ntransform = [";
        for (size_t k = 0; k < 12; ++k) {
            // Row-major 3x4: the translations (k = 3, 7, 11) in the file's coordinates.
            const double v = t.m[k] + (k % 4 == 3 ? o[k / 4] : 0.0);
            std::snprintf(buf, sizeof buf, "%s%.17g", k ? ", " : "", v);
            os << buf;
        }
        os << "]\n";
    }
    for (const Measurement& m : st.measurements) {
        if (!m.b) continue;
        os << "\n[[measurement]]\na = " << triple(m.a[0], m.a[1], m.a[2]) << "\nb = " << triple((*m.b)[0], (*m.b)[1], (*m.b)[2])
           << "\n";
    }
    return os.str();
}

namespace {

SessionState parseSessionState(const toml::table& root, const std::filesystem::path& name, const SceneDesc& scene) {
    using namespace toml_reader;
    const std::array<double, 3>& o = scene.origin;
    auto rel = [&](const std::array<double, 3>& p) {
        return Float3{float(p[0] - o[0]), float(p[1] - o[1]), float(p[2] - o[2])};
    };
    auto readCamera = [&](Reader& r, CameraDesc& c) {
        c.position = rel(r.vec3d("position", {}, true));
        c.lookAt = rel(r.vec3d("look_at", {}, true));
        c.up = r.vec3("up", c.up);
        if (length(c.up) == 0) r.fail(r.find("up"), "key 'up': must not be zero");
        c.fovY = float(r.number("fov", c.fovY, 0.01, 179.0));
        if (c.position == c.lookAt) r.fail(r.find("look_at"), "key 'look_at': must differ from 'position'");
    };
    SessionState st;
    Reader top(name, root, "");
    const toml::table* cam = subTable(top, "camera");
    if (!cam) throw InputError(name.string() + ": a session needs a [camera]");
    {
        Reader r(name, *cam, "[camera]: ");
        st.camera = scene.cameras.empty() ? CameraDesc{} : scene.cameras.front();
        readCamera(r, st.camera);
        r.finish();
    }
    forEachTable(top, name, "bookmark", [&](Reader& r, const toml::table&) {
        Bookmark b;
        b.name = r.string("name", "", true);
        if (b.name.empty() || b.name.size() > 200) r.fail(r.find("name"), "key 'name': 1 to 200 characters");
        for (const Bookmark& e : st.bookmarks)
            if (e.name == b.name) r.fail(r.find("name"), "key 'name': bookmark '" + b.name + "' is given twice");
        b.camera = st.camera;
        readCamera(r, b.camera);
        st.bookmarks.push_back(b);
    });
    if (const toml::table* t = subTable(top, "parts")) {
        Reader r(name, *t, "[parts]: ");
        auto list = [&](const char* key) {
            std::vector<std::string> v;
            if (const toml::node* n = r.find(key)) {
                const toml::array* a = n->as_array();
                if (!a) r.fail(n, std::string("key '") + key + "': expected an array of strings");
                for (const toml::node& e : *a) {
                    if (!e.is_string()) r.fail(n, std::string("key '") + key + "': expected strings");
                    v.push_back(e.as_string()->get());
                }
            }
            return v;
        };
        st.parts.hide = list("hide");
        st.parts.isolate = list("isolate");
        st.parts.highlight = list("highlight");
        r.finish();
        try {
            visibilityOf(scene, st.parts);
        } catch (const InputError& e) {
            throw InputError(where(name, t->source()) + ": [parts]: " + e.what());
        }
    }
    std::array<bool, kMaxSections> slots{};
    forEachTable(top, name, "section", [&](Reader& r, const toml::table&) {
        const int slot = r.integer("slot", 0, 0, kMaxSections - 1);
        if (slots[size_t(slot)]) r.fail(r.find("slot"), "key 'slot': slot " + std::to_string(slot) + " is given twice");
        slots[size_t(slot)] = true;
        SectionPlane p;
        p.enabled = r.boolean("enabled", true);
        p.point = rel(r.vec3d("point", {}, true));
        p.normal = r.vec3("normal", {}, true);
        if (length(p.normal) == 0) r.fail(r.find("normal"), "key 'normal': must not be zero");
        p.capColor = r.vec3("cap_color", p.capColor);
        p.caps = r.boolean("caps", p.caps);
        st.sections[size_t(slot)] = p;
    });
    forEachTable(top, name, "moved", [&](Reader& r, const toml::table& t) {
        const int i = r.integer("instance", 0, 0, std::numeric_limits<int>::max());
        if (size_t(i) >= scene.instances.size())
            r.fail(r.find("instance"), "key 'instance': " + std::to_string(i) + " does not exist (the scene has " +
                                           std::to_string(scene.instances.size()) + " instances)");
        if (!st.moved.empty() && uint32_t(i) <= st.moved.back().first)
            r.fail(r.find("instance"), "key 'instance': instances must be given in increasing order, each once");
        const toml::node* n = r.find("transform");
        const toml::array* a = n ? n->as_array() : nullptr;
        if (!a || a->size() != 12) r.fail(n ? n : static_cast<const toml::node*>(&t), "key 'transform': expected 12 numbers (a row-major 3x4 matrix)");
        Transform tr;
        for (size_t k = 0; k < 12; ++k) {
            const std::optional<double> v = (*a)[k].value<double>();
            if (!v || !std::isfinite(*v)) r.fail(n, "key 'transform': expected 12 finite numbers");
            tr.m[k] = *v - (k % 4 == 3 ? o[k / 4] : 0.0);
        }
        st.moved.emplace_back(uint32_t(i), tr);
    });
    forEachTable(top, name, "measurement", [&](Reader& r, const toml::table&) {
        Measurement m;
        m.a = r.vec3d("a", {}, true);
        m.b = r.vec3d("b", {}, true);
        const double dx = (*m.b)[0] - m.a[0], dy = (*m.b)[1] - m.a[1], dz = (*m.b)[2] - m.a[2];
        m.distance = std::sqrt(dx * dx + dy * dy + dz * dz);
        st.measurements.push_back(m);
    });
    top.finish();
    return st;
}

}  // namespace

SessionState parseSessionState(std::string_view text, const std::string& name, const SceneDesc& scene) {
    toml::table root;
    try {
        root = toml::parse(text, name);
    } catch (const toml::parse_error& e) {
        throw InputError(toml_reader::where(name, e.source()) + ": " + std::string(e.description()));
    }
    return parseSessionState(root, name, scene);
}

SessionState readSessionState(const std::filesystem::path& file, const SceneDesc& scene) {
    return parseSessionState(toml_reader::parseFile(file), file, scene);
}

}  // namespace rtwall
