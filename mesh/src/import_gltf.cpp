// glTF 2.0 (.gltf, .glb) as an assembly, through Debian's tinygltf shared library.
//
// tinygltf parses the JSON, the GLB framing and the buffers (data URIs, the GLB BIN chunk,
// external files); everything it hands over is then checked here before any of it is read:
// accessors against their buffer views, buffer views against their buffers, indices against the
// vertex count. Images are not decoded here (the engine decodes PNG and JPEG textures): an image
// loader callback keeps the encoded bytes. External files are read by our own callbacks, which
// accept regular files only, so a URI naming a device or a FIFO cannot make the import hang.
#include "rtwall/mesh.h"

#include "assembly_import.h"
#include "mesh_internal.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <new>
#include <string>
#include <system_error>
#include <utility>

namespace rtwall {
namespace {

namespace fs = std::filesystem;
using Matrix = detail::Affine;
using detail::composeAffine;

// More instances than this is an input error, not an allocation: a small file can name a mesh
// of many primitives from many nodes (the same bound as a scene file's instances).
constexpr uint64_t kMaxInstances = uint64_t(1) << 24;
constexpr uint32_t kNoMesh = UINT32_MAX;  // a primitive without triangles

[[noreturn]] void fail(const std::string& name, const std::string& what) { throw InputError(name + ": " + what); }

// tinygltf's messages may span lines; an InputError is one.
std::string oneLine(std::string s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
    for (size_t i = 0; i < s.size(); ++i)
        if (s[i] == '\n') s.replace(i, 1, "; ");
    return s;
}

Matrix fromTrs(const double t[3], const double q[4], const double s[3]) {
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
                         2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                         2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
    return {r[0] * s[0], r[1] * s[1], r[2] * s[2], t[0], r[3] * s[0], r[4] * s[1], r[5] * s[2], t[1],
            r[6] * s[0], r[7] * s[1], r[8] * s[2], t[2]};
}

// A transform its instance cannot be traced through: one that squashes the mesh flat (a zero
// scale), or whose matrix or inverse float cannot hold (Embree traces instances through float
// matrices and their inverses). Such an instance would only give NaN rays.
bool singularInFloat(const Matrix& m) {
    double f[12];
    for (int i = 0; i < 12; ++i) {
        f[i] = double(float(m[size_t(i)]));
        if (!std::isfinite(float(m[size_t(i)]))) return true;
    }
    const double c00 = f[5] * f[10] - f[6] * f[9], c01 = f[6] * f[8] - f[4] * f[10], c02 = f[4] * f[9] - f[5] * f[8];
    const double det = f[0] * c00 + f[1] * c01 + f[2] * c02;
    if (!std::isfinite(det) || det == 0) return true;
    // The inverse's elements are the cofactors over the determinant.
    const double cof[9] = {c00, c01, c02, f[2] * f[9] - f[1] * f[10], f[0] * f[10] - f[2] * f[8], f[1] * f[8] - f[0] * f[9],
                           f[1] * f[6] - f[2] * f[5], f[2] * f[4] - f[0] * f[6], f[0] * f[5] - f[1] * f[4]};
    for (double c : cof)
        if (!std::isfinite(float(c / det))) return true;
    return false;
}

// Linear [0, 1] to the 8-bit sRGB encoding TriangleMesh colours use.
uint8_t encodeSrgb(float linear) {
    const float c = std::clamp(std::isfinite(linear) ? linear : 0.0f, 0.0f, 1.0f);
    const float s = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
    return uint8_t(std::lround(s * 255.0f));
}

struct ExternalFiles {
    bool allowed = true;
};

bool fileExists(const std::string& path, void*) {
    std::error_code ec;
    return fs::is_regular_file(path, ec);
}
std::string expandPath(const std::string& path, void*) { return path; }
bool readWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
    if (!static_cast<ExternalFiles*>(user)->allowed) {
        if (err) *err += "external file '" + path + "' is not read here";
        return false;
    }
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        if (err) *err += "'" + path + "' is not a regular file";
        return false;
    }
    std::ifstream in(path, std::ios::binary);
    const uintmax_t size = fs::file_size(path, ec);
    if (!in || ec) {
        if (err) *err += "cannot open '" + path + "'";
        return false;
    }
    out->resize(size_t(size));
    if (size > 0 && !in.read(reinterpret_cast<char*>(out->data()), std::streamsize(size))) {
        if (err) *err += "cannot read '" + path + "'";
        return false;
    }
    return true;
}
bool writeWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err += "writing is not supported";
    return false;
}

// Keeps the encoded image bytes: the engine decodes textures itself (PNG, JPEG). tinygltf 2.7
// hands an image's buffer view over without checking that the view lies inside its buffer (found
// by fuzz_import_gltf: a read past the buffer), so the view is checked here, against the model it
// is filling (`user`), before a byte of it is read.
bool keepImageBytes(tinygltf::Image* image, const int index, std::string* err, std::string*, int, int,
                    const unsigned char* bytes, int size, void* user) {
    if (image->bufferView >= 0) {
        const auto& model = *static_cast<const tinygltf::Model*>(user);
        const auto& views = model.bufferViews;
        bool inside = size_t(image->bufferView) < views.size();
        if (inside) {
            const tinygltf::BufferView& v = views[size_t(image->bufferView)];
            inside = v.buffer >= 0 && size_t(v.buffer) < model.buffers.size() && v.byteLength <= size_t(INT32_MAX);
            if (inside) {
                const size_t n = model.buffers[size_t(v.buffer)].data.size();
                inside = v.byteOffset <= n && v.byteLength <= n - v.byteOffset;
            }
        }
        if (!inside) {
            if (err) *err += "image " + std::to_string(index) + ": buffer view " + std::to_string(image->bufferView) + " lies outside its buffer";
            return false;
        }
    }
    image->image.assign(bytes, bytes + std::max(size, 0));
    image->as_is = true;
    return true;
}

class GltfReader {
public:
    GltfReader(const tinygltf::Model& model, const std::string& name, Assembly& out) : m_(model), name_(name), out_(out) {}

    void read() {
        readMaterials();
        std::vector<int> roots;
        if (!m_.scenes.empty()) {
            const int s = m_.defaultScene >= 0 ? m_.defaultScene : 0;
            if (size_t(s) >= m_.scenes.size()) fail(name_, "scene " + std::to_string(s) + " does not exist");
            roots = m_.scenes[size_t(s)].nodes;
        } else {
            // No scene: every node that is nobody's child is a root.
            std::vector<bool> child(m_.nodes.size(), false);
            for (const tinygltf::Node& n : m_.nodes)
                for (int c : n.children)
                    if (c >= 0 && size_t(c) < child.size()) child[size_t(c)] = true;
            for (size_t i = 0; i < m_.nodes.size(); ++i)
                if (!child[i]) roots.push_back(int(i));
        }
        visited_.assign(m_.nodes.size(), false);
        for (int r : roots) visit(r, -1, Matrix{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0});
        // One line per node whose instances were left out, however many (GPU instancing).
        for (const auto& [node, count] : singular_)
            out_.warnings.push_back(name_ + ": node " + std::to_string(node) + ": " + std::to_string(count) +
                                    (count == 1 ? " instance" : " instances") +
                                    " with a singular transform (a zero scale) left out: nothing can be traced through it");
    }

private:
    std::map<int, size_t> singular_;  // instances left out for a singular transform, by node

    struct View {
        const unsigned char* data = nullptr;
        size_t stride = 0, count = 0, components = 0;
        int componentType = 0;
        bool normalized = false;
    };

    std::string accessorName(int index) const { return "accessor " + std::to_string(index); }

    // The accessor's elements, after checking that every byte of them lies inside its buffer view
    // and the view inside its buffer.
    View accessor(int index, const std::string& what) const {
        if (index < 0 || size_t(index) >= m_.accessors.size())
            fail(name_, what + ": accessor " + std::to_string(index) + " does not exist");
        const tinygltf::Accessor& a = m_.accessors[size_t(index)];
        const std::string an = what + ": " + accessorName(index);
        if (a.sparse.isSparse) fail(name_, an + " is sparse, which is not supported");
        if (a.bufferView < 0 || size_t(a.bufferView) >= m_.bufferViews.size())
            fail(name_, an + ": buffer view " + std::to_string(a.bufferView) + " does not exist");
        const tinygltf::BufferView& bv = m_.bufferViews[size_t(a.bufferView)];
        const std::string bvn = "buffer view " + std::to_string(a.bufferView);
        if (bv.buffer < 0 || size_t(bv.buffer) >= m_.buffers.size())
            fail(name_, an + ": " + bvn + ": buffer " + std::to_string(bv.buffer) + " does not exist");
        const std::vector<unsigned char>& buf = m_.buffers[size_t(bv.buffer)].data;
        if (bv.byteOffset > buf.size() || bv.byteLength > buf.size() - bv.byteOffset)
            fail(name_, an + ": " + bvn + " (bytes " + std::to_string(bv.byteOffset) + " + " + std::to_string(bv.byteLength) +
                            ") lies outside buffer " + std::to_string(bv.buffer) + " (" + std::to_string(buf.size()) + " bytes)");
        const int components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        const int componentSize = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        if (components <= 0 || componentSize <= 0) fail(name_, an + " has an unknown type or component type");
        View v;
        v.components = size_t(components);
        v.componentType = a.componentType;
        v.normalized = a.normalized;
        const size_t element = v.components * size_t(componentSize);
        v.stride = bv.byteStride ? bv.byteStride : element;
        if (v.stride < element) fail(name_, an + ": byte stride " + std::to_string(v.stride) + " is less than an element");
        v.count = a.count;
        if (v.count > 0) {
            const size_t room = bv.byteLength;
            if (a.byteOffset > room || element > room - a.byteOffset || (v.count - 1) > (room - a.byteOffset - element) / v.stride)
                fail(name_, an + ": " + std::to_string(v.count) + " elements from byte " + std::to_string(a.byteOffset) +
                                " do not fit " + bvn + " (" + std::to_string(room) + " bytes)");
            v.data = buf.data() + bv.byteOffset + a.byteOffset;
        }
        return v;
    }

    static float component(const View& v, size_t element, size_t c) {
        const unsigned char* p = v.data + element * v.stride;
        switch (v.componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: {
            float f;
            std::memcpy(&f, p + 4 * c, 4);
            return f;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return v.normalized ? p[c] / 255.0f : float(p[c]);
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            const auto b = int8_t(p[c]);
            return v.normalized ? std::max(b / 127.0f, -1.0f) : float(b);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t u;
            std::memcpy(&u, p + 2 * c, 2);
            return v.normalized ? u / 65535.0f : float(u);
        }
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t s;
            std::memcpy(&s, p + 2 * c, 2);
            return v.normalized ? std::max(s / 32767.0f, -1.0f) : float(s);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
            uint32_t u;
            std::memcpy(&u, p + 4 * c, 4);
            return float(u);
        }
        default: return 0.0f;
        }
    }

    static uint32_t index(const View& v, size_t element) {
        const unsigned char* p = v.data + element * v.stride;
        switch (v.componentType) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return p[0];
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t u;
            std::memcpy(&u, p, 2);
            return u;
        }
        default: {
            uint32_t u;
            std::memcpy(&u, p, 4);
            return u;
        }
        }
    }

    void readMaterials() {
        for (size_t i = 0; i < m_.materials.size(); ++i) {
            const tinygltf::Material& g = m_.materials[i];
            AssemblyMaterial a;
            a.name = g.name.empty() ? "material " + std::to_string(i) : g.name;
            const auto& pbr = g.pbrMetallicRoughness;
            for (size_t c = 0; c < 4 && c < pbr.baseColorFactor.size(); ++c) a.baseColor[c] = float(pbr.baseColorFactor[c]);
            a.metallic = float(pbr.metallicFactor);
            a.roughness = float(pbr.roughnessFactor);
            for (size_t c = 0; c < 3 && c < g.emissiveFactor.size(); ++c) a.emissive[c] = float(g.emissiveFactor[c]);
            if (auto t = g.extensions.find("KHR_materials_transmission"); t != g.extensions.end()) {
                a.transmission = 0.0f;  // the extension's default factor
                if (t->second.Has("transmissionFactor") && t->second.Get("transmissionFactor").IsNumber())
                    a.transmission = float(t->second.Get("transmissionFactor").GetNumberAsDouble());
            }
            if (auto t = g.extensions.find("KHR_materials_ior"); t != g.extensions.end())
                if (t->second.Has("ior") && t->second.Get("ior").IsNumber()) a.ior = float(t->second.Get("ior").GetNumberAsDouble());
            for (float* f : {&a.metallic, &a.roughness, &a.transmission})
                if (!std::isfinite(*f)) fail(name_, "material " + std::to_string(i) + ": a factor is not a finite number");
            a.metallic = std::clamp(a.metallic, 0.0f, 1.0f);
            a.roughness = std::clamp(a.roughness, 0.0f, 1.0f);
            a.transmission = std::clamp(a.transmission, 0.0f, 1.0f);
            if (!(a.ior >= 1.0f && a.ior <= 10.0f)) fail(name_, "material " + std::to_string(i) + ": ior must lie in [1, 10]");
            a.alphaMode = g.alphaMode == "MASK"    ? AssemblyMaterial::Alpha::Mask
                          : g.alphaMode == "BLEND" ? AssemblyMaterial::Alpha::Blend
                                                   : AssemblyMaterial::Alpha::Opaque;
            if (g.alphaMode != "OPAQUE" && g.alphaMode != "MASK" && g.alphaMode != "BLEND")
                fail(name_, "material " + std::to_string(i) + ": alphaMode '" + g.alphaMode + "' is not OPAQUE, MASK or BLEND");
            a.alphaCutoff = float(g.alphaCutoff);
            if (!(a.alphaCutoff >= 0.0f && a.alphaCutoff <= 1.0f))
                fail(name_, "material " + std::to_string(i) + ": alphaCutoff must lie in [0, 1]");
            a.doubleSided = g.doubleSided;
            if (pbr.baseColorTexture.index >= 0) a.baseColorTexture = imageKey(pbr.baseColorTexture.index, i);
            if (pbr.baseColorTexture.index >= 0 && pbr.baseColorTexture.texCoord != 0)
                out_.warnings.push_back(name_ + ": material " + std::to_string(i) +
                                        ": the base colour texture uses TEXCOORD_" + std::to_string(pbr.baseColorTexture.texCoord) +
                                        "; TEXCOORD_0 is used");
            out_.materials.push_back(std::move(a));
        }
    }

    std::string imageKey(int texture, size_t material) {
        const std::string where = "material " + std::to_string(material) + ": texture " + std::to_string(texture);
        if (size_t(texture) >= m_.textures.size()) fail(name_, where + " does not exist");
        const int source = m_.textures[size_t(texture)].source;
        if (source < 0 || size_t(source) >= m_.images.size()) fail(name_, where + ": image " + std::to_string(source) + " does not exist");
        const tinygltf::Image& img = m_.images[size_t(source)];
        if (img.image.empty())
            fail(name_, where + ": image " + std::to_string(source) + (img.uri.empty() ? "" : " ('" + img.uri + "')") +
                            " could not be read");
        const std::string key = name_ + "#image" + std::to_string(source);
        if (!out_.files.count(key)) out_.files[key] = std::make_shared<const std::vector<uint8_t>>(img.image.begin(), img.image.end());
        return key;
    }

    uint32_t defaultMaterial() { return detail::defaultAssemblyMaterial(out_, defaultMaterial_); }

    // What makes a primitive's triangles: its accessors (POSITION, NORMAL, COLOR_0, TEXCOORD_0,
    // indices; -1 where absent) and its mode. Writers often give each copy of a part a glTF mesh
    // of its own over the same accessors; primitives of equal keys are one TriangleMesh, whatever
    // glTF mesh holds them and whatever material each uses (materials are per instance here).
    using PrimitiveKey = std::array<int, 6>;
    static PrimitiveKey primitiveKey(const tinygltf::Primitive& p) {
        auto attribute = [&](const char* name) {
            const auto a = p.attributes.find(name);
            return a == p.attributes.end() ? -1 : a->second;
        };
        return {attribute("POSITION"), attribute("NORMAL"), attribute("COLOR_0"), attribute("TEXCOORD_0"), p.indices, p.mode};
    }

    // One TriangleMesh per distinct primitive key, built the first time a node uses it.
    uint32_t primitiveMesh(size_t mesh, size_t prim) {
        const tinygltf::Primitive& p = m_.meshes[mesh].primitives[prim];
        const PrimitiveKey key = primitiveKey(p);
        if (auto it = meshOf_.find(key); it != meshOf_.end()) return it->second;
        const std::string where = "mesh " + std::to_string(mesh) + " primitive " + std::to_string(prim);
        auto pos = p.attributes.find("POSITION");
        if (pos == p.attributes.end()) fail(name_, where + " has no POSITION");
        const View P = accessor(pos->second, where + " POSITION");
        if (P.components != 3) fail(name_, where + " POSITION is not a VEC3");
        TriangleMesh tm;
        const size_t n = P.count;
        if (n > UINT32_MAX) fail(name_, where + " has more than 2^32 vertices");
        auto& positions = detail::MeshAccess::positions(tm);
        std::vector<float> xyz(3 * n);
        for (size_t v = 0; v < n; ++v)
            for (size_t c = 0; c < 3; ++c) {
                const float f = component(P, v, c);
                if (!std::isfinite(f)) fail(name_, where + " POSITION " + std::to_string(v) + " is not finite");
                xyz[3 * v + c] = f;
            }
        positions.assign(std::move(xyz));
        detail::MeshAccess::setVertexCount(tm, n);

        if (auto a = p.attributes.find("NORMAL"); a != p.attributes.end()) {
            const View N = accessor(a->second, where + " NORMAL");
            if (N.components != 3 || N.count != n) fail(name_, where + " NORMAL is not a VEC3 per vertex");
            std::vector<float> normals(3 * n);
            bool usable = true;
            for (size_t v = 0; v < n && usable; ++v) {
                const float x = component(N, v, 0), y = component(N, v, 1), z = component(N, v, 2);
                const float len = std::sqrt(x * x + y * y + z * z);
                usable = std::isfinite(len) && len > 0.0f;
                if (usable) {
                    normals[3 * v] = x / len;
                    normals[3 * v + 1] = y / len;
                    normals[3 * v + 2] = z / len;
                }
            }
            if (usable) tm.setNormals(std::move(normals));
            else out_.warnings.push_back(name_ + ": " + where + ": a normal is zero or not finite; the normals are dropped");
        }
        if (auto a = p.attributes.find("COLOR_0"); a != p.attributes.end()) {
            const View C = accessor(a->second, where + " COLOR_0");
            if ((C.components != 3 && C.components != 4) || C.count != n) fail(name_, where + " COLOR_0 is not a VEC3/VEC4 per vertex");
            std::vector<uint8_t> rgb(3 * n);
            for (size_t v = 0; v < n; ++v)
                for (size_t c = 0; c < 3; ++c) rgb[3 * v + c] = encodeSrgb(component(C, v, c));
            tm.setColors(std::move(rgb));
        }
        if (auto a = p.attributes.find("TEXCOORD_0"); a != p.attributes.end()) {
            const View T = accessor(a->second, where + " TEXCOORD_0");
            if (T.components != 2 || T.count != n) fail(name_, where + " TEXCOORD_0 is not a VEC2 per vertex");
            std::vector<float> uv(2 * n);
            for (size_t v = 0; v < n; ++v) {
                // glTF's v runs down the image from its top row; rtwall's up from the bottom row.
                uv[2 * v] = component(T, v, 0);
                uv[2 * v + 1] = 1.0f - component(T, v, 1);
                if (!std::isfinite(uv[2 * v]) || !std::isfinite(uv[2 * v + 1]))
                    fail(name_, where + " TEXCOORD_0 " + std::to_string(v) + " is not finite");
            }
            tm.setUVs(std::move(uv));
        }

        // Corner list: the index accessor, or 0 .. n-1.
        std::vector<uint32_t> corners;
        if (p.indices >= 0) {
            const View I = accessor(p.indices, where + " indices");
            if (I.components != 1 || (I.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                       I.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                                       I.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
                fail(name_, where + " indices are not unsigned integer scalars");
            corners.resize(I.count);
            for (size_t i = 0; i < I.count; ++i) {
                corners[i] = index(I, i);
                if (corners[i] >= n)
                    fail(name_, where + " index " + std::to_string(i) + " = " + std::to_string(corners[i]) + " is out of range (" +
                                    std::to_string(n) + " vertices)");
            }
        } else {
            corners.resize(n);
            for (size_t i = 0; i < n; ++i) corners[i] = uint32_t(i);
        }
        std::vector<uint32_t> tri;
        switch (p.mode) {
        case TINYGLTF_MODE_TRIANGLES:
            if (corners.size() % 3 != 0) fail(name_, where + ": " + std::to_string(corners.size()) + " corners are not whole triangles");
            tri = std::move(corners);
            break;
        case TINYGLTF_MODE_TRIANGLE_STRIP:
            for (size_t i = 2; i < corners.size(); ++i) {
                const bool odd = (i & 1) != 0;  // every other triangle is wound the other way
                tri.insert(tri.end(), {corners[i - 2 + odd], corners[i - 1 - odd], corners[i]});
            }
            break;
        case TINYGLTF_MODE_TRIANGLE_FAN:
            for (size_t i = 2; i < corners.size(); ++i) tri.insert(tri.end(), {corners[i - 1], corners[i], corners[0]});
            break;
        default:
            // Points and lines have nothing to render; the mesh stays empty.
            out_.warnings.push_back(name_ + ": " + where + " is points or lines (mode " + std::to_string(p.mode) + "), skipped");
            break;
        }
        if (tri.empty()) {
            // Nothing to render (points, lines, or no triangles): no mesh, no instances.
            meshOf_[key] = kNoMesh;
            return kNoMesh;
        }
        detail::MeshAccess::indices(tm).assign(std::move(tri));
        // Meshes far from their own origin are stored recentred; the instance transform puts
        // origin() back in double precision.
        detail::recentre(tm);

        const uint32_t id = uint32_t(out_.meshes.size());
        out_.meshes.push_back(std::make_shared<const TriangleMesh>(std::move(tm)));
        const std::string& meshName = m_.meshes[mesh].name;
        out_.meshNames.push_back((meshName.empty() ? "mesh " + std::to_string(mesh) : meshName) +
                                 (m_.meshes[mesh].primitives.size() > 1 ? "/" + std::to_string(prim) : ""));
        meshOf_[key] = id;
        return id;
    }

    Matrix localTransform(const tinygltf::Node& n, int index) const {
        const std::string where = "node " + std::to_string(index);
        if (!n.matrix.empty()) {
            if (n.matrix.size() != 16) fail(name_, where + ": matrix must have 16 numbers");
            const auto& c = n.matrix;  // column-major
            for (double v : c)
                if (!std::isfinite(v)) fail(name_, where + ": matrix is not finite");
            return {c[0], c[4], c[8], c[12], c[1], c[5], c[9], c[13], c[2], c[6], c[10], c[14]};
        }
        double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
        if (!n.translation.empty() && n.translation.size() != 3) fail(name_, where + ": translation must have 3 numbers");
        if (!n.rotation.empty() && n.rotation.size() != 4) fail(name_, where + ": rotation must have 4 numbers");
        if (!n.scale.empty() && n.scale.size() != 3) fail(name_, where + ": scale must have 3 numbers");
        std::copy(n.translation.begin(), n.translation.end(), t);
        std::copy(n.rotation.begin(), n.rotation.end(), q);
        std::copy(n.scale.begin(), n.scale.end(), s);
        for (double v : {t[0], t[1], t[2], q[0], q[1], q[2], q[3], s[0], s[1], s[2]})
            if (!std::isfinite(v)) fail(name_, where + ": translation, rotation or scale is not finite");
        return fromTrs(t, q, s);
    }

    void addInstances(int node, int mesh, uint32_t part, const Matrix& world) {
        if (mesh < 0) return;
        if (singularInFloat(world)) {
            ++singular_[node];
            return;
        }
        if (size_t(mesh) >= m_.meshes.size()) fail(name_, "node " + std::to_string(node) + ": mesh " + std::to_string(mesh) + " does not exist");
        const auto& prims = m_.meshes[size_t(mesh)].primitives;
        if (out_.instances.size() + prims.size() > kMaxInstances)
            fail(name_, "more than " + std::to_string(kMaxInstances) + " mesh instances");
        for (size_t p = 0; p < prims.size(); ++p) {
            AssemblyInstance in;
            in.mesh = primitiveMesh(size_t(mesh), p);
            if (in.mesh == kNoMesh) continue;
            const int mat = prims[p].material;
            if (mat >= 0 && size_t(mat) >= m_.materials.size())
                fail(name_, "mesh " + std::to_string(mesh) + " primitive " + std::to_string(p) + ": material " +
                                std::to_string(mat) + " does not exist");
            in.material = mat >= 0 ? uint32_t(mat) : defaultMaterial();
            in.part = part;
            const auto& o = out_.meshes[in.mesh]->origin();
            in.transform = composeAffine(world, Matrix{1, 0, 0, o[0], 0, 1, 0, o[1], 0, 0, 1, o[2]});
            out_.instances.push_back(in);
        }
    }

    // EXT_mesh_gpu_instancing: the node's mesh once per element of its TRS accessors.
    bool gpuInstances(const tinygltf::Node& n, int node, uint32_t part, const Matrix& world) {
        auto ext = n.extensions.find("EXT_mesh_gpu_instancing");
        if (ext == n.extensions.end() || !ext->second.Has("attributes")) return false;
        const tinygltf::Value& attrs = ext->second.Get("attributes");
        const std::string where = "node " + std::to_string(node) + " EXT_mesh_gpu_instancing";
        View views[3];
        const char* names[3] = {"TRANSLATION", "ROTATION", "SCALE"};
        const size_t wantComponents[3] = {3, 4, 3};
        size_t count = SIZE_MAX;
        for (int k = 0; k < 3; ++k) {
            if (!attrs.Has(names[k])) continue;
            const tinygltf::Value& v = attrs.Get(names[k]);
            if (!v.IsInt()) fail(name_, where + ": " + names[k] + " is not an accessor index");
            views[k] = accessor(v.GetNumberAsInt(), where + " " + names[k]);
            if (views[k].components != wantComponents[k]) fail(name_, where + ": " + names[k] + " has the wrong type");
            if (count != SIZE_MAX && views[k].count != count) fail(name_, where + ": the attributes have different counts");
            count = views[k].count;
        }
        if (count == SIZE_MAX) return false;
        for (size_t i = 0; i < count; ++i) {
            double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
            for (size_t c = 0; views[0].data && c < 3; ++c) t[c] = component(views[0], i, c);
            for (size_t c = 0; views[1].data && c < 4; ++c) q[c] = component(views[1], i, c);
            for (size_t c = 0; views[2].data && c < 3; ++c) s[c] = component(views[2], i, c);
            for (double v : {t[0], t[1], t[2], q[0], q[1], q[2], q[3], s[0], s[1], s[2]})
                if (!std::isfinite(v)) fail(name_, where + ": instance " + std::to_string(i) + " is not finite");
            addInstances(node, n.mesh, part, composeAffine(world, fromTrs(t, q, s)));
        }
        return true;
    }

    void visit(int root, int parentPart, const Matrix& parentWorld) {
        // Depth first with an explicit stack, so a deep chain of nodes cannot exhaust the call stack.
        struct Item {
            int node, parentPart;
            Matrix parentWorld;
        };
        std::vector<Item> stack{{root, parentPart, parentWorld}};
        while (!stack.empty()) {
            const Item it = stack.back();
            stack.pop_back();
            if (it.node < 0 || size_t(it.node) >= m_.nodes.size()) fail(name_, "node " + std::to_string(it.node) + " does not exist");
            if (visited_[size_t(it.node)])
                fail(name_, "node " + std::to_string(it.node) + " is reached twice (the nodes must form trees)");
            visited_[size_t(it.node)] = true;
            const tinygltf::Node& n = m_.nodes[size_t(it.node)];
            const Matrix world = composeAffine(it.parentWorld, localTransform(n, it.node));
            const auto part = uint32_t(out_.parts.size());
            out_.parts.push_back({n.name.empty() ? "node " + std::to_string(it.node) : n.name, it.parentPart});
            if (!gpuInstances(n, it.node, part, world)) addInstances(it.node, n.mesh, part, world);
            for (auto c = n.children.rbegin(); c != n.children.rend(); ++c) stack.push_back({*c, int(part), world});
        }
    }

    const tinygltf::Model& m_;
    const std::string& name_;
    Assembly& out_;
    std::vector<bool> visited_;
    std::map<PrimitiveKey, uint32_t> meshOf_;
    int defaultMaterial_ = -1;
};

Assembly decode(const unsigned char* data, size_t size, const std::string& name, const fs::path& baseDir, bool external) {
    if (size > UINT32_MAX) fail(name, "larger than 4 GiB, which glTF cannot address");
    tinygltf::TinyGLTF loader;
    ExternalFiles files{external};
    loader.SetFsCallbacks({&fileExists, &expandPath, &readWholeFile, &writeWholeFile, &files});
    tinygltf::Model model;
    loader.SetImageLoader(&keepImageBytes, &model);
    std::string err, warn;
    const bool binary = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
    bool ok = false;
    try {
        ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, data, unsigned(size), baseDir.string())
                    : loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(data), unsigned(size),
                                                 baseDir.string());
    } catch (const std::bad_alloc&) {
        fail(name, "out of memory while parsing");
    } catch (const std::exception& e) {
        fail(name, oneLine(e.what()));
    }
    if (!ok) fail(name, oneLine(err.empty() ? "not a valid glTF file" : err));
    Assembly out;
    out.format = binary ? "glb" : "gltf";
    if (!warn.empty()) out.warnings.push_back(name + ": " + oneLine(warn));
    GltfReader(model, name, out).read();
    return out;
}

}  // namespace

Assembly decodeGltf(const unsigned char* data, size_t size, const std::string& name) {
    return decode(data, size, name, {}, false);
}

namespace detail {

Assembly importGltf(const fs::path& file) {
    std::vector<unsigned char> bytes;
    std::string err;
    ExternalFiles files;
    if (!readWholeFile(&bytes, &err, file.string(), &files)) fail(file.string(), err);
    return decode(bytes.data(), bytes.size(), file.string(), file.parent_path(), true);
}

}  // namespace detail
}  // namespace rtwall
