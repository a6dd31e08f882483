// Run configs (format: configs/README.md, "Run configs"): what `rtwall run` runs, read strictly
// (unknown keys and wrong types are one-line errors naming the file and line).
#include <rtwall/toml_reader.h>
#include <rtwall/wall.h>

namespace rtwall {

namespace {

// Used when `rtwall run` is given no config: the built-in knot field, two local clients.
constexpr const char* kEmbeddedDefault = R"(scene = "builtin:knots"
[image]
width = 800
height = 600
[cluster]
clients = 2
[run]
frames = 60
write_every = 30
orbit = 1.0
)";

void readCluster(toml_reader::Reader& r, const std::filesystem::path& dir, ClusterSettings& cs) {
    cs.bind = r.string("bind", cs.bind);
    cs.localClients = r.integer("clients", cs.localClients, 0, 256);
    cs.threadsPerClient = r.integer("threads", cs.threadsPerClient, 0, 1024);
    cs.prefetch = r.integer("prefetch", cs.prefetch, 1, 64);
    cs.affinity = r.boolean("affinity", cs.affinity);
    cs.async = r.boolean("async", cs.async);
    cs.codec.codec = tileCodecFromName(r.choice("codec", "lz4", {"raw", "lz4", "zstd", "jpeg"}));
    cs.codec.jpegQuality = r.integer("jpeg_quality", cs.codec.jpegQuality, 1, 100);
    cs.codec.jpegSubsample = r.boolean("jpeg_subsample", cs.codec.jpegSubsample);
    cs.codec.zstdLevel = r.integer("zstd_level", cs.codec.zstdLevel, 1, 19);
    cs.heartbeatMs = r.integer("heartbeat_ms", cs.heartbeatMs, 10, 60000);
    cs.timeoutMs = r.integer("timeout_ms", cs.timeoutMs, 50, 600000);
    cs.stragglerFactor = r.number("straggler_factor", cs.stragglerFactor, 1.0, 1000.0);
    cs.wideAccumulation = r.boolean("wide_accumulation", cs.wideAccumulation);
    if (cs.timeoutMs <= cs.heartbeatMs) r.fail(r.find("timeout_ms"), "timeout_ms must exceed heartbeat_ms");
    const std::string key = r.string("key", "");
    if (!key.empty()) cs.keyFile = dir / key;
    if (const toml::node* n = r.find("client_keys")) {
        const toml::array* a = n->as_array();
        if (!a) r.fail(n, "key 'client_keys': expected an array of public key files");
        for (const toml::node& e : *a) {
            if (!e.is_string()) r.fail(n, "key 'client_keys': expected strings");
            cs.clientKeys.push_back(dir / std::string(*e.value<std::string>()));
        }
    }
    cs.insecure = r.boolean("insecure", cs.insecure);
}

// Paths in a config are relative to its folder.
RunConfig readRunConfig(const std::filesystem::path& file, const toml::table& root) {
    using namespace toml_reader;
    const std::filesystem::path dir = file.parent_path();
    RunConfig c;
    Reader top(file, root, "");
    const std::string scene = top.string("scene", c.scene);
    c.scene = scene.starts_with("builtin:") || file.empty() ? scene : (dir / scene).string();
    c.camera = top.string("camera", "");
    if (const std::string wall = top.string("wall", ""); !wall.empty()) c.wall = dir / wall;
    if (const toml::table* t = subTable(top, "image")) {
        Reader r(file, *t, "[image]: ");
        c.width = r.integer("width", 0, 1, 16384);
        c.height = r.integer("height", 0, 1, 16384);
        r.finish();
    }
    if (const toml::table* t = subTable(top, "cluster")) {
        Reader r(file, *t, "[cluster]: ");
        readCluster(r, dir, c.cluster);
        c.localDisplayNodes = r.boolean("local_display_nodes", c.localDisplayNodes);
        r.finish();
    }
    if (const toml::table* t = subTable(top, "run")) {
        Reader r(file, *t, "[run]: ");
        c.frames = r.integer("frames", c.frames, 0, 100'000'000);
        c.writeEvery = r.integer("write_every", c.writeEvery, 0, 100'000'000);
        c.out = r.string("out", c.out.string());
        c.orbit = r.number("orbit", c.orbit, -360.0, 360.0);
        if (r.has("camera_path")) {
            if (r.has("orbit")) r.fail(r.find("camera_path"), "give either 'orbit' or 'camera_path'");
            c.cameraPath = dir / r.string("camera_path", "");
            c.orbit = 0.0;
        }
        r.finish();
    }
    top.finish();
    return c;
}

}  // namespace

RunConfig readRunConfig(const std::filesystem::path& file) { return readRunConfig(file, toml_reader::parseFile(file)); }

RunConfig defaultRunConfig() { return readRunConfig({}, toml::parse(kEmbeddedDefault)); }

}  // namespace rtwall
