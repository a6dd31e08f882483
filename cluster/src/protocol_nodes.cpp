// Display nodes on the wire (version 11): a node's hello and welcome, a frame's layout, the swap
// barrier's have, swap and swapped, and the node list clients send tiles by; the re-projecting
// wall's pose every refresh and the node's answer (version 15); how a node denoises a frame
// (version 17); pictures of what the nodes show (version 20).
#include "protocol_values.h"

#include <rtwall/denoise.h>

#include <zstd.h>

#include <algorithm>

namespace rtwall::cluster {

namespace {

constexpr size_t kMaxEndpointBytes = 256;
constexpr size_t kZ85KeyChars = 40;

template <class Io, class S> void nodeName(Io& io, S& name, const char* what) {
    io.string(name, 32);
    io.expect(isNodeName(name), [&] {
        return std::string(what) + " '" + name + "' is not a node name (1 to 32 letters, digits, '-' or '_')";
    });
}

template <class Io, class S> void endpoint(Io& io, S& e) {
    io.string(e, kMaxEndpointBytes);
    io.expect(!e.empty(), [] { return std::string("empty node endpoint"); });
    io.expect(std::all_of(e.begin(), e.end(), [](char c) { return c > ' ' && c <= '~'; }),
              [] { return std::string("node endpoint has a control, space or non-ASCII character"); });
}

bool z85(char c) {
    return c > ' ' && c < '~' && c != '"' && c != '\'' && c != ',' && c != ';' && c != '\\' && c != '_' && c != '`' &&
           c != '|';
}

// A CURVE key: Z85 (40 characters) or empty (no CURVE).
template <class Io, class S> void key(Io& io, S& k, const char* what) {
    io.string(k, kZ85KeyChars);
    io.expect(k.empty() || k.size() == kZ85KeyChars, [&] {
        return std::string(what) + " has " + std::to_string(k.size()) + " characters, not 40 (Z85) or 0";
    });
    io.expect(std::all_of(k.begin(), k.end(), z85), [&] { return std::string(what) + " is not Z85"; });
}

template <class Io, class N> void nodeIndex(Io& io, N& node) {
    io.u32(node);
    io.expect(node < kMaxNodes,
              [&] { return "node index " + std::to_string(node) + " is not below " + std::to_string(kMaxNodes); });
}

}  // namespace

bool isNodeName(const std::string& name) {
    if (name.empty() || name.size() > 32) return false;
    for (char c : name)
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_'))
            return false;
    return true;
}

RTWALL_WIRE_MESSAGE(NodeHello, 4) {
    io.u16(m.protocolVersion);  // returned as read, so that the master can name both versions
    nodeName(io, m.name, "node name");
    endpoint(io, m.endpoint);
    key(io, m.publicKey, "node public key");
}

RTWALL_WIRE_MESSAGE(NodeWelcome, 6) {
    nodeIndex(io, m.node);
    io.u32(m.heartbeatMs);
    io.u32(m.timeoutMs);
    io.expect(m.heartbeatMs >= 1 && m.heartbeatMs <= kMaxTimeoutMs && m.timeoutMs >= m.heartbeatMs &&
                  m.timeoutMs <= kMaxTimeoutMs,
              [&] {
                  return "node heartbeat " + std::to_string(m.heartbeatMs) + " ms and timeout " +
                         std::to_string(m.timeoutMs) + " ms are out of range";
              });
    io.string(m.wall, kMaxWallConfigBytes);
    io.expect(!m.wall.empty(), [] { return std::string("node welcome without a wall config"); });
    io.sequence(
        m.clientKeys, sizeof(uint32_t) + kZ85KeyChars, kMaxClientKeys,
        [&](auto& k) {
            key(io, k, "client key");
            io.expect(!k.empty(), [] { return std::string("empty client key"); });
        },
        SendLimit::Strict);
    io.trailing(m.reproject, [&] {
        io.boolean(m.reproject);
        io.expect(m.reproject, [] { return std::string("a re-projection flag that says no (it is left out then)"); });
    });
}

RTWALL_WIRE_FIELDS(DenoiseSettings, 6) {
    io.enumUpTo(m.mode, DenoiseSettings::Mode::Svgf, "denoise mode");
    io.intIn(m.levels, 1, 10, "denoise levels");
    io.intIn(m.history, 1, 65536, "denoise history");
    io.floatIn(m.sigmaDepth, 1e-6f, 1e6f, "denoise sigma_depth");
    io.floatIn(m.sigmaNormal, 0.0f, 1e6f, "denoise sigma_normal");
    io.floatIn(m.sigmaLuminance, 1e-6f, 1e6f, "denoise sigma_luminance");
}

RTWALL_WIRE_FIELDS(NodeDenoise, 5) {
    fields(io, m.settings);
    io.expect(m.settings.mode != DenoiseSettings::Mode::Off, [] { return std::string("a denoised frame with mode off"); });
    io.intIn(m.ring, 0, kMaxImageSide, "denoise ring");
    io.u8(m.features);
    io.expect(m.features != 0 && m.features <= kFeatureAll && (featureBitsFor(m.settings.mode) & ~m.features) == 0, [&] {
        return "feature bits " + std::to_string(int(m.features)) + " for denoise mode " + denoiseModeName(m.settings.mode);
    });
    io.u32(m.sceneSeq);
    fields(io, m.camera);
}

RTWALL_WIRE_MESSAGE(NodeFrame, 12) {
    static const size_t viewBytes = minViewBytes();
    io.u32(m.frame);
    io.intIn(m.width, 1, kMaxImageSide, "node frame width");
    io.intIn(m.height, 1, kMaxImageSide, "node frame height");
    io.intIn(m.tileSize, 1, kMaxTileSize, "node frame tile size");
    uint64_t tiles = 0;
    if constexpr (Io::decoding) {
        tiles = uint64_t((m.width + m.tileSize - 1) / m.tileSize) * uint64_t((m.height + m.tileSize - 1) / m.tileSize);
        if (tiles > kMaxTilesPerFrame) fail("node frame of " + std::to_string(tiles) + " tiles exceeds the limit");
    }
    io.enumUpTo(m.pixels, TilePixels::LinearHalf, "tile pixel format");
    vectorOf(io, m.views, viewBytes, kMaxViews);
    // Every view may hold every tile: the node's tiling is bounded as one frame's.
    io.expect(tiles * std::max<uint64_t>(1, m.views.size()) <= kMaxTilesPerFrame, [&] {
        return "node frame of " + std::to_string(m.views.size()) + " views of " + std::to_string(tiles) +
               " tiles exceeds the limit";
    });
    const auto eyeCount = [&](uint32_t eyes) {
        if (eyes != m.views.size())
            fail("node frame with " + std::to_string(eyes) + " view eyes for " + std::to_string(m.views.size()) + " views");
    };
    const auto eye = [&](auto& value) {
        uint8_t e = uint8_t(value);
        io.u8(e);
        io.expect(e == 0 || e == 1 || e == 0xff,
                  [&] { return "view eye " + std::to_string(int(int8_t(e))) + " is not -1, 0 or 1"; });
        if constexpr (Io::decoding) value = int8_t(e);
    };
    io.sequence(m.eyes, 1, kMaxViews, eye, SendLimit::Strict, eyeCount);
    io.boolean(m.stochastic);
    io.u32(m.stateSeq);
    io.expect(m.pixels != TilePixels::LinearHalf || m.stochastic,
              [] { return std::string("linear tiles for a frame that is not accumulated"); });
    // Version 21: one byte says which optional parts follow (bit 0: its tiles carry depth, bit 1:
    // the denoise settings, bit 2: the room eyes), so that each may come without the others.
    uint8_t tail = uint8_t((m.depth ? 1 : 0) | (m.denoise ? 2 : 0) | (m.roomEyes ? 4 : 0));
    io.u8(tail);
    io.expect(tail < 8, [&] { return "node frame parts " + std::to_string(int(tail)); });
    if constexpr (Io::decoding) m.depth = (tail & 1) != 0;
    if (tail & 2) {
        if constexpr (Io::decoding) m.denoise.emplace();
        fields(io, *m.denoise);
        io.expect(m.depth && m.pixels == TilePixels::LinearHalf,
                  [] { return std::string("a denoised frame without depth or linear tiles"); });
    }
    if (tail & 4) {
        if constexpr (Io::decoding) m.roomEyes.emplace();
        io.float3((*m.roomEyes)[0]);
        io.float3((*m.roomEyes)[1]);
    }
}

RTWALL_WIRE_MESSAGE(NodeHave, 1) { io.u32(m.frame); }

RTWALL_WIRE_MESSAGE(NodeSwap, 2) {
    io.u32(m.frame);
    io.sequence(m.leftOut, sizeof(uint32_t) + 1, kMaxNodes, [&](auto& name) { nodeName(io, name, "left-out node"); },
                SendLimit::Strict);
}

RTWALL_WIRE_MESSAGE(NodeSwapped, 1) { io.u32(m.frame); }

RTWALL_WIRE_MESSAGE(NodePose, 5) {
    static const size_t cameraBytes = [] {
        CameraDesc c;
        c.name.clear();
        return minEncodedSize(c);
    }();
    io.u32(m.refresh);
    io.u32(m.frame);
    io.boolean(m.debug);
    vectorOf(io, m.cameras, cameraBytes, kMaxViews, SendLimit::Strict);
    io.expect(!m.cameras.empty(), [] { return std::string("a node pose without cameras"); });
    bool eyes = m.roomEyes.has_value();  // version 21: last, left out when absent
    io.trailing(eyes, [&] {
        if constexpr (Io::decoding) m.roomEyes.emplace();
        io.float3((*m.roomEyes)[0]);
        io.float3((*m.roomEyes)[1]);
    });
}

RTWALL_WIRE_MESSAGE(NodeShown, 1) { io.u32(m.refresh); }

RTWALL_WIRE_MESSAGE(WarpGrids, 1) {
    // Each grid is at least its 13-byte head and one sample.
    vectorOf(io, m.grids, 1 + 4 + 4 + 4 + 12, kMaxWarpGrids);
}

RTWALL_WIRE_MESSAGE(NodePreviewAsk, 3) {
    io.u32(m.id);
    io.intIn(m.width, 1, kMaxImageSide, "preview width");
    io.u64(m.nodes);
    io.expect(m.nodes != 0, [] { return std::string("a preview asked of no display node"); });
}

RTWALL_WIRE_MESSAGE(NodePreview, 12) {
    io.u32(m.id);
    io.u32(m.frame);
    io.u8(m.eye);
    io.expect(m.eye <= 1, [&] { return "preview eye " + std::to_string(m.eye); });
    io.intIn(m.srcWidth, 0, kMaxImageSide, "preview frame width");
    io.intIn(m.srcHeight, 0, kMaxImageSide, "preview frame height");
    io.intIn(m.x0, 0, kMaxImageSide, "preview cell x0");
    io.intIn(m.y0, 0, kMaxImageSide, "preview cell y0");
    io.intIn(m.x1, m.x0, kMaxImageSide, "preview cell x1");
    io.intIn(m.y1, m.y0, kMaxImageSide, "preview cell y1");
    io.u8(m.valueBytes);
    io.expect(m.valueBytes == 1 || m.valueBytes == 2 || m.valueBytes == 4,
              [&] { return "preview values of " + std::to_string(m.valueBytes) + " bytes"; });
    io.boolean(m.last);
    static const size_t maxBlob = ZSTD_compressBound(kMaxPreviewPartBytes);
    io.blob(m.cells, maxBlob);
    const size_t cells = size_t(m.x1 - m.x0) * size_t(m.y1 - m.y0);
    io.expect(cells * 4 * m.valueBytes <= kMaxPreviewPartBytes,
              [&] { return "a preview part of " + std::to_string(cells) + " cells (at most " +
                           std::to_string(kMaxPreviewPartBytes) + " bytes a part)"; });
    io.expect((cells == 0) == m.cells.empty(), [] { return std::string("preview cells that do not match their rectangle"); });
    io.expect(m.frame != 0 || (cells == 0 && m.last), [] { return std::string("cells of no frame"); });
    io.expect(m.frame == 0 || (m.srcWidth > 0 && m.srcHeight > 0), [] { return std::string("a preview of an empty frame"); });
}

RTWALL_WIRE_FIELDS(NodeEndpoint, 4) {
    nodeIndex(io, m.node);
    nodeName(io, m.name, "node name");
    endpoint(io, m.endpoint);
    key(io, m.serverKey, "node server key");
}

RTWALL_WIRE_MESSAGE(NodeList, 1) {
    static const size_t endpointBytes = minEncodedSize(NodeEndpoint{});
    vectorOf(io, m.nodes, endpointBytes, kMaxNodes, SendLimit::Strict);
    if constexpr (Io::decoding) {
        uint64_t seen = 0;
        for (const NodeEndpoint& e : m.nodes) {
            if (seen & (uint64_t(1) << e.node)) fail("node " + std::to_string(e.node) + " is twice in the node list");
            seen |= uint64_t(1) << e.node;
        }
    }
}

}  // namespace rtwall::cluster
