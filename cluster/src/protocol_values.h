// The scene values messages carry (materials, lights, cameras, instances, settings, mesh and asset
// references, frame views): their wire fields, once for both directions (message_fields.h).
// Internal to the protocol code, like message_fields.h.
#pragma once

#include "message_fields.h"

namespace rtwall::cluster {

// More ranges the engine relies on (message_fields.h has those the messages share).
inline constexpr int kMaxDepth = 64;
inline constexpr int kMaxSupersample = 16;
inline constexpr int kMaxViewReference = 1 << 20;  // a view region's reference image (the wall's pixels)

inline bool finite(const Float3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

RTWALL_WIRE_FIELDS(CodecSettings, 4) {
    io.enumUpTo(m.codec, TileCodec::Jpeg, "tile codec");
    io.intIn(m.jpegQuality, 1, 100, "JPEG quality");
    io.boolean(m.jpegSubsample);
    io.intIn(m.zstdLevel, 1, 19, "zstd level");
}

RTWALL_WIRE_FIELDS(Transform, 1) {
    for (auto& v : m.m) io.f64(v);  // finite
}

RTWALL_WIRE_FIELDS(TextureDesc, 5) {
    io.enumUpTo(m.kind, TextureKind::Image, "texture kind");
    // Clients open texture files themselves (a shared file system), like mesh sources.
    io.string(m.file, kMaxStringBytes);
    io.unitColor(m.color2, "texture color2");
    io.f32(m.scale);
    io.expect(m.scale > 0.0f && std::isfinite(m.scale), [&] { return "texture scale " + std::to_string(m.scale) + " is not positive"; });
    io.enumUpTo(m.mapping, TextureMapping::Auto, "texture mapping");
}

RTWALL_WIRE_FIELDS(TransferPoint, 3) {  // written with the material
    io.f32(m.value);
    io.expect(std::isfinite(m.value), [] { return std::string("transfer function value is not finite"); });
    io.nonNegativeColor(m.color, "transfer function colour");
    io.floatIn(m.density, 0.0f, 3.4e38f, "transfer function density");
}

RTWALL_WIRE_FIELDS(Material, 22) {
    io.string(m.name, kMaxStringBytes);
    io.enumUpTo(m.type, MaterialType::Volume, "material type");
    io.unitColor(m.color, "material color");
    io.unitColor(m.specular, "material specular");
    io.f32(m.shininess);
    // A negative exponent makes pow() blow up at grazing angles.
    io.expect(m.shininess >= 0.0f, [&] { return "material shininess " + std::to_string(m.shininess) + " is negative"; });
    io.f32(m.ior);
    io.expect(m.ior >= 1.0f && m.ior <= 4.0f, [&] { return "material ior " + std::to_string(m.ior) + " is outside [1, 4]"; });
    io.floatIn(m.roughness, 0.0f, 1.0f, "material roughness");
    io.nonNegativeColor(m.absorption, "material absorption");
    io.nonNegativeColor(m.emission, "material emission");
    fields(io, m.texture);
    io.floatIn(m.bump, 0.0f, 100.0f, "material bump");
    io.floatIn(m.bumpScale, 1e-6f, 1e6f, "material bump scale");
    io.enumUpTo(m.bumpMapping, TextureMapping::Object, "bump mapping");  // version 5
    io.expect(m.bumpMapping == TextureMapping::Auto || m.bumpMapping == TextureMapping::Uv ||
                  m.bumpMapping == TextureMapping::Object,
              [] { return std::string("bump mapping must be auto, uv or object"); });
    fields(io, m.alpha);
    io.floatIn(m.alphaCutoff, 0.0f, 1.0f, "material alpha cutoff");
    io.string(m.volumeFile, kMaxStringBytes);
    io.sequence(m.transfer, 0, std::numeric_limits<uint32_t>::max(), [&](auto& p) { fields(io, p); }, SendLimit::U32,
                [](uint32_t points) {
                    if (points > 4096) fail("transfer function of " + std::to_string(points) + " points exceeds the limit");
                });
    io.floatIn(m.volumeStep, 0.01f, 100.0f, "volume step");
    io.boolean(m.twoSided);  // version 6
    io.enumUpTo(m.alphaMode, AlphaMode::Hashed, "alpha mode");  // version 19
    io.enumUpTo(m.alphaChannel, AlphaChannel::Alpha, "alpha channel");
    io.floatIn(m.opacity, 0.0f, 1.0f, "material opacity");
    // A volume material without a file cannot be built; refuse it here rather than in the engine.
    io.expect(m.type != MaterialType::Volume || !m.volumeFile.empty(), [] { return std::string("volume material without a volume file"); });
    io.expect(m.texture.kind != TextureKind::Image || !m.texture.file.empty(), [] { return std::string("image texture without a file"); });
    io.expect(m.alpha.kind != TextureKind::Image || !m.alpha.file.empty(), [] { return std::string("image alpha mask without a file"); });
}

RTWALL_WIRE_FIELDS(Light, 8) {
    io.enumUpTo(m.type, LightType::Area, "light type");
    for (auto* v : {&m.position, &m.direction, &m.edge1, &m.edge2, &m.color}) io.float3(*v);
    io.f32(m.intensity);
    io.expect(m.intensity >= 0.0f, [&] { return "light intensity " + std::to_string(m.intensity) + " is negative"; });
    io.boolean(m.twoSided);  // version 6
}

RTWALL_WIRE_FIELDS(SectionPlane, 5) {
    io.boolean(m.enabled);
    io.float3(m.point);
    io.float3(m.normal);
    io.expect(finite(m.point) && finite(m.normal), [] { return std::string("section plane is not finite"); });
    io.expect(m.normal.x * m.normal.x + m.normal.y * m.normal.y + m.normal.z * m.normal.z > 0.0f,
              [] { return std::string("section plane normal is zero"); });
    io.unitColor(m.capColor, "section cap colour");
    io.boolean(m.caps);
}

RTWALL_WIRE_COUNT(ProjectionWindow, 3);  // written with the camera
RTWALL_WIRE_FIELDS(CameraDesc, 6) {
    io.string(m.name, kMaxStringBytes);
    io.float3(m.position);
    io.float3(m.lookAt);
    io.float3(m.up);
    io.f32(m.fovY);
    io.expect(m.fovY > 0.0f && m.fovY < 180.0f, [&] { return "camera fov " + std::to_string(m.fovY) + " is outside (0, 180)"; });
    bool window = m.window.has_value();
    io.boolean(window);
    if constexpr (Io::decoding) m.window = window ? std::optional<ProjectionWindow>(ProjectionWindow{}) : std::nullopt;
    if (!window) return;
    io.float3(m.window->lowerLeft);
    io.float3(m.window->right);
    io.float3(m.window->up);
    io.expect(finite(m.window->lowerLeft) && finite(m.window->right) && finite(m.window->up),
              [] { return std::string("camera window is not finite"); });
}

RTWALL_WIRE_FIELDS(InstanceDesc, 6) {
    io.u32(m.mesh);
    io.u32(m.material);
    fields(io, m.transform);
    // The part's index only: the names stay with the master (SceneDesc::parts does not travel),
    // so a client can say which part a failed tile shows to the master, which can name it.
    io.i32(m.part);
    io.expect(m.part >= -1, [&] { return "instance part " + std::to_string(m.part) + " is out of range"; });
    io.enumUpTo(m.visibility, Visibility::Highlighted, "instance visibility");
    io.boolean(m.movable);  // version 20
}

RTWALL_WIRE_FIELDS(RenderSettings, 15) {  // what is each process's own is TraceOptions, not sent
    io.intIn(m.width, 1, kMaxImageSide, "image width");
    io.intIn(m.height, 1, kMaxImageSide, "image height");
    io.intIn(m.tileSize, 1, kMaxTileSize, "tile size");
    io.enumUpTo(m.kernel, KernelType::Single, "kernel type");
    io.enumUpTo(m.shading, ShadingMode::EyeLight, "shading mode");
    io.intIn(m.maxDepth, 1, kMaxDepth, "max depth");
    io.intIn(m.supersample, 1, kMaxSupersample, "supersample");
    io.boolean(m.shadows);
    io.float3(m.background);
    io.float3(m.ambient);
    io.intIn(m.threads, 0, kMaxThreads, "thread count");
    io.floatIn(m.pruneThreshold, 0.0f, 1.0f, "prune threshold");
    io.boolean(m.gi);
    io.intIn(m.samples, 1, 4096, "samples");
    io.enumUpTo(m.view, ViewMode::Client, "view mode");
}

RTWALL_WIRE_FIELDS(MeshRef, 4) {
    io.string(m.name, kMaxStringBytes);
    io.string(m.source, kMaxStringBytes);
    io.hash(m.hash);
    io.u64(m.bytes);
    io.expect(m.bytes <= kMaxMeshBytes, [&] { return "mesh size " + std::to_string(m.bytes) + " exceeds the limit"; });
}

RTWALL_WIRE_FIELDS(AssetRef, 3) {
    io.string(m.path, kMaxStringBytes);
    io.expect(!m.path.empty(), [] { return std::string("asset with an empty path"); });
    io.hash(m.hash);
    io.u64(m.bytes);
    io.expect(m.bytes <= kMaxAssetBytes, [&] { return "asset size " + std::to_string(m.bytes) + " exceeds the limit"; });
}

RTWALL_WIRE_FIELDS(ViewRegion, 4) {
    // The bounds of the view's reference image are checked with the view.
    io.intIn(m.x, 0, kMaxViewReference, "view region x");
    io.intIn(m.y, 0, kMaxViewReference, "view region y");
    io.intIn(m.width, 0, kMaxViewReference, "view region width");
    io.intIn(m.height, 0, kMaxViewReference, "view region height");
}

RTWALL_WIRE_FIELDS(RoomToWorld, 6) {
    io.float3(m.origin);
    io.float3(m.viewer);
    io.float3(m.x);
    io.float3(m.y);
    io.float3(m.z);
    io.floatIn(m.scale, 1e-9f, 1e9f, "room scale");
}

RTWALL_WIRE_FIELDS(WarpRef, 3) {
    io.u32(m.grid);
    io.expect(m.grid < kMaxWarpGrids, [&] { return "warp grid " + std::to_string(m.grid) + " exceeds the limit"; });
    fields(io, m.rect);
    fields(io, m.room);
}

RTWALL_WIRE_FIELDS(FrameView, 5) {
    fields(io, m.camera);
    vectorOf(io, m.regions, 16, kMaxRegionsPerView);
    vectorOf(io, m.warps, 4 + 16 + 64, kMaxWarpsPerView);
    const bool regions = !m.regions.empty() || !m.warps.empty();
    // Without regions or warps the view is the whole image and the reference size means nothing.
    io.intIn(m.refWidth, regions ? 1 : 0, kMaxViewReference, "view reference width");
    io.intIn(m.refHeight, regions ? 1 : 0, kMaxViewReference, "view reference height");
    const auto inside = [&](const ViewRegion& g, const char* what) {
        io.expect(int64_t(g.x) + g.width <= m.refWidth && int64_t(g.y) + g.height <= m.refHeight, [&] {
            return std::string(what) + " " + std::to_string(g.x) + "," + std::to_string(g.y) + "," +
                   std::to_string(g.width) + "," + std::to_string(g.height) + " is outside its " +
                   std::to_string(m.refWidth) + "x" + std::to_string(m.refHeight) + " reference image";
        });
    };
    for (const ViewRegion& g : m.regions) inside(g, "view region");
    for (const WarpRef& w : m.warps) inside(w.rect, "warp rectangle");
}

// A projector's warp grid: NaN marks a pixel on no screen; infinity is never a place.
RTWALL_WIRE_FIELDS(PixelWarp, 4) {
    io.enumUpTo(m.kind, PixelWarp::Kind::SurfacePoints, "warp kind");
    io.intIn(m.width, 1, kMaxWarpSide, "warp grid width");
    io.intIn(m.height, 1, kMaxWarpSide, "warp grid height");
    const uint64_t count = uint64_t(m.width) * uint64_t(m.height);
    io.sequence(m.samples, 12, kMaxWarpSamples, [&](auto& v) { io.float3OrNaN(v); }, SendLimit::U32, [&](uint32_t n) {
        io.expect(n == count, [&] {
            return "warp grid of " + std::to_string(m.width) + "x" + std::to_string(m.height) + " has " +
                   std::to_string(n) + " samples";
        });
    });
}

// The smallest encoding of a FrameView: a bound on the views a message can hold.
inline size_t minViewBytes() {
    FrameView v;
    v.camera.name.clear();
    return minEncodedSize(v);
}

}  // namespace rtwall::cluster
