// Assembly caches (STEP/IGES), beside the mesh caches of cache.cpp whose format each of their
// meshes keeps.
#include "cache_io.h"
#include "mesh_internal.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>

// -----------------------------------------------------------------------------------------------
// Assembly caches (STEP/IGES): the tessellated parts and the assembly around them, keyed by the
// source file's content (XXH3-64 and size) and the tessellation deflections, so that a second
// load skips OCCT entirely. Layout, little-endian:
//   0   "RTWASM01"           8   u32 version, u32 0
//   16  u64 content hash     24  u64 source size
//   32  f64 linear deflection 40 f64 angular deflection
//   48  u64 XXH3-64 of the whole file with these 8 bytes taken as zero
//   56  u64 bytes of the description that follows the header
//   64  description: format; mesh names; materials; parts; instances; per mesh (offset, size)
//   then each mesh as a mesh cache (the format above), 64-byte aligned, so it is mapped in place.
namespace rtwall {

namespace fs = std::filesystem;
using namespace detail::cacheio;

namespace {

constexpr char kAssemblyMagic[8] = {'R', 'T', 'W', 'A', 'S', 'M', '0', '1'};
constexpr uint32_t kAssemblyVersion = 1;
constexpr size_t kAssemblyHeader = 64, kAssemblyChecksumAt = 48;

class Out {
public:
    std::vector<unsigned char> bytes;
    template <class T>
    void put(T v) {
        const size_t at = bytes.size();
        bytes.resize(at + sizeof(T));
        if constexpr (std::is_floating_point_v<T>) {
            using U = std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>;
            putLE(bytes.data() + at, std::bit_cast<U>(v));
        } else {
            putLE(bytes.data() + at, v);
        }
    }
    void str(const std::string& s) {
        put(uint32_t(s.size()));
        bytes.insert(bytes.end(), s.begin(), s.end());
    }
};

// Reads the description with every length checked against what is left, so a corrupt count
// fails before anything is allocated for it.
class In {
public:
    In(const unsigned char* data, size_t size, size_t at, const std::string& name) : d_(data), size_(size), at_(at), name_(name) {}
    template <class T>
    T get() {
        need(sizeof(T));
        at_ += sizeof(T);
        if constexpr (std::is_floating_point_v<T>) {
            using U = std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>;
            return std::bit_cast<T>(getLE<U>(d_ + at_ - sizeof(T)));
        } else {
            return getLE<T>(d_ + at_ - sizeof(T));
        }
    }
    float finite() {
        const auto f = get<float>();
        if (!std::isfinite(f)) fail("a value is not finite");
        return f;
    }
    std::string str() {
        const auto n = get<uint32_t>();
        need(n);
        std::string s(reinterpret_cast<const char*>(d_ + at_), n);
        at_ += n;
        return s;
    }
    // An element count, each element at least `minBytes` long.
    size_t count(size_t minBytes) {
        const auto n = get<uint64_t>();
        if (n > (size_ - at_) / minBytes) fail("a count does not fit the file");
        return size_t(n);
    }
    [[noreturn]] void fail(const std::string& what) const { throw InputError(name_ + ":offset " + std::to_string(at_) + ": " + what); }
    size_t at() const { return at_; }

private:
    void need(size_t n) const {
        if (n > size_ - at_) fail("truncated");
    }
    const unsigned char* d_;
    size_t size_, at_;
    const std::string& name_;
};

}  // namespace

namespace detail {

fs::path assemblyCachePath(const fs::path& source, const fs::path& cacheDir) {
    fs::path p = meshCachePath(source, cacheDir);
    return p.replace_extension(".rtwasm");
}

uint64_t hashFileContent(const fs::path& file, uint64_t& size) {
    const Mapping map(file);
    if (!map.ok()) throw InputError(file.string() + ": cannot open the file");
    size = map.size();
    return map.data() ? XXH3_64bits(map.data(), map.size()) : XXH3_64bits(nullptr, 0);
}

std::vector<unsigned char> encodeAssemblyCache(const Assembly& a, const AssemblyKey& key) {
    Out d;
    d.str(a.format);
    d.put(uint64_t(a.meshNames.size()));
    for (const std::string& n : a.meshNames) d.str(n);
    d.put(uint64_t(a.materials.size()));
    for (const AssemblyMaterial& m : a.materials) {
        d.str(m.name);
        for (float f : m.baseColor) d.put(f);
        d.put(m.metallic);
        d.put(m.roughness);
        for (float f : m.emissive) d.put(f);
        d.put(m.transmission);
        d.put(m.ior);
        d.str(m.baseColorTexture);
    }
    d.put(uint64_t(a.parts.size()));
    for (const AssemblyPart& p : a.parts) {
        d.str(p.name);
        d.put(p.parent);
    }
    d.put(uint64_t(a.instances.size()));
    for (const AssemblyInstance& in : a.instances) {
        d.put(in.mesh);
        d.put(in.material);
        d.put(in.part);
        for (double v : in.transform) d.put(v);
    }
    std::vector<std::vector<unsigned char>> meshes;
    for (const auto& m : a.meshes) meshes.push_back(encodeMeshCache(*m, ImportReport{}, key.size, 0));
    size_t at = align64(kAssemblyHeader + d.bytes.size() + 16 * meshes.size());
    const size_t described = d.bytes.size() + 16 * meshes.size();
    std::vector<size_t> offsets;
    for (const auto& m : meshes) {
        offsets.push_back(at);
        d.put(uint64_t(at));
        d.put(uint64_t(m.size()));
        at = align64(at + m.size());
    }
    std::vector<unsigned char> file(at, 0);
    std::memcpy(file.data(), kAssemblyMagic, 8);
    putLE(file.data() + 8, kAssemblyVersion);
    putLE(file.data() + 16, key.hash);
    putLE(file.data() + 24, key.size);
    putLE(file.data() + 32, std::bit_cast<uint64_t>(key.linearDeflection));
    putLE(file.data() + 40, std::bit_cast<uint64_t>(key.angularDeflection));
    putLE(file.data() + 56, uint64_t(described));
    std::memcpy(file.data() + kAssemblyHeader, d.bytes.data(), d.bytes.size());
    for (size_t i = 0; i < meshes.size(); ++i) std::memcpy(file.data() + offsets[i], meshes[i].data(), meshes[i].size());
    putLE(file.data() + kAssemblyChecksumAt, checksumAt(file.data(), file.size(), kAssemblyChecksumAt));
    return file;
}

void writeAssemblyCache(const Assembly& a, const AssemblyKey& key, const fs::path& cacheFile) {
    const std::vector<unsigned char> bytes = encodeAssemblyCache(a, key);
    writeAssemblyCacheBytes(bytes.data(), bytes.size(), cacheFile);
}

void writeAssemblyCacheBytes(const unsigned char* data, size_t size, const fs::path& cacheFile) {
    const fs::path tmp = cacheFile.string() + ".tmp." + std::to_string(::getpid());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
        out.flush();
        if (!out) {
            out.close();
            std::error_code ec;
            fs::remove(tmp, ec);
            throw InputError(cacheFile.string() + ": cannot write the cache");
        }
    }
    std::error_code ec;
    fs::rename(tmp, cacheFile, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw InputError(cacheFile.string() + ": cannot write the cache: " + ec.message());
    }
}

Assembly decodeAssemblyCache(const unsigned char* data, size_t size, const AssemblyKey& key, const std::string& name,
                             std::shared_ptr<const void> keepAlive) {
    if (size < kAssemblyHeader) throw InputError(name + ": truncated: shorter than the header");
    if (std::memcmp(data, kAssemblyMagic, 8) != 0) throw InputError(name + ": not an rtwall assembly cache");
    if (getLE<uint32_t>(data + 8) != kAssemblyVersion) throw InputError(name + ": another cache version");
    if (getLE<uint64_t>(data + 16) != key.hash || getLE<uint64_t>(data + 24) != key.size)
        throw InputError(name + ": stale: the source file's content changed since the cache was written");
    if (getLE<uint64_t>(data + 32) != std::bit_cast<uint64_t>(key.linearDeflection) ||
        getLE<uint64_t>(data + 40) != std::bit_cast<uint64_t>(key.angularDeflection))
        throw InputError(name + ": made with other tessellation deflections");
    if (getLE<uint64_t>(data + kAssemblyChecksumAt) != checksumAt(data, size, kAssemblyChecksumAt))
        throw InputError(name + ": checksum mismatch (corrupt)");
    const uint64_t described = getLE<uint64_t>(data + 56);
    if (described > size - kAssemblyHeader) throw InputError(name + ": the description does not fit the file");
    In in(data, kAssemblyHeader + size_t(described), kAssemblyHeader, name);
    Assembly a;
    a.format = in.str();
    a.meshNames.resize(in.count(4));
    for (std::string& n : a.meshNames) n = in.str();
    a.materials.resize(in.count(52));
    for (AssemblyMaterial& m : a.materials) {
        m.name = in.str();
        for (float& f : m.baseColor) f = in.finite();
        m.metallic = in.finite();
        m.roughness = in.finite();
        for (float& f : m.emissive) f = in.finite();
        m.transmission = in.finite();
        m.ior = in.finite();
        m.baseColorTexture = in.str();
        if (!m.baseColorTexture.empty()) in.fail("a cached material names a texture");  // CAD files have none
    }
    a.parts.resize(in.count(8));
    for (size_t i = 0; i < a.parts.size(); ++i) {
        a.parts[i].name = in.str();
        a.parts[i].parent = in.get<int32_t>();
        if (a.parts[i].parent < -1 || a.parts[i].parent >= int32_t(i)) in.fail("a part's parent does not come before it");
    }
    a.instances.resize(in.count(108));
    for (AssemblyInstance& i : a.instances) {
        i.mesh = in.get<uint32_t>();
        i.material = in.get<uint32_t>();
        i.part = in.get<uint32_t>();
        for (double& v : i.transform) {
            v = in.get<double>();
            if (!std::isfinite(v)) in.fail("a transform is not finite");
        }
        if (i.mesh >= a.meshNames.size() || i.material >= a.materials.size() || i.part >= a.parts.size())
            in.fail("an instance names a mesh, material or part that does not exist");
    }
    for (size_t m = 0; m < a.meshNames.size(); ++m) {
        const auto off = in.get<uint64_t>(), bytes = in.get<uint64_t>();
        if (off % 64 != 0 || off < kAssemblyHeader + described || off > size || bytes > size - off)
            in.fail("mesh " + std::to_string(m) + " lies outside the file");
        a.meshes.push_back(std::make_shared<const TriangleMesh>(
            decodeMeshCache(data + off, size_t(bytes), key.size, 0, name + " mesh " + std::to_string(m), nullptr, keepAlive)));
    }
    if (in.at() != kAssemblyHeader + described) in.fail("unexpected bytes after the description");
    return a;
}

std::optional<Assembly> readAssemblyCache(const fs::path& cacheFile, const AssemblyKey& key, std::string* whyNot) {
    auto no = [&](const std::string& why) -> std::optional<Assembly> {
        if (whyNot) *whyNot = why;
        return std::nullopt;
    };
    const auto map = std::make_shared<const Mapping>(cacheFile);
    if (!map->ok()) return no("no cache");
    if (!map->data()) return no("the cache is empty or cannot be mapped");
    try {
        Assembly a = decodeAssemblyCache(map->data(), map->size(), key, cacheFile.string(), map);
        map->accessRandomly();
        return a;
    } catch (const InputError& e) {
        return no(e.what());
    } catch (const std::bad_alloc&) {
        return no("out of memory reading the cache");
    }
}

}  // namespace detail
}  // namespace rtwall
