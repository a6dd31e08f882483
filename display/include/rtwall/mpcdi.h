// MPCDI (VESA Multiple Projector Common Data Interchange, issue 30): the calibration a
// camera-based tool exports for a projector array, read from its `.mpcdi` file (a zip holding
// mpcdi.xml, PFM geometry warps and PNG alpha/beta blend maps). Reading only: what the wall
// makes of it (rays through each projector pixel, blending in the compositor) is the wall's.
//
// Where the standard leaves details loose, this reader follows the readers real calibrations
// are tested with (docs/mpcdi.md):
// - attribute and element names match without regard to case (`Xresolution`, `xResolution`;
//   `fileset`, `fileSet`), and a fileset is found under <files> (MPCDI 2.0) or in its region;
// - PFM rows are stored bottom to top (the PFM format); here every grid is top row first, as
//   the projector's pixels are;
// - a warp or map of W x H samples covers the region edge to edge with its samples at pixel
//   centres: sample (i, j) belongs to the region point ((i + 0.5) / W, (j + 0.5) / H) from the
//   top left, so a grid of the region's resolution is one sample per projector pixel;
// - 2D-profile warps hold (u, v, unused) in [0, 1], u to the right and v up from the lower left
//   of the screen (texture coordinates, as PFM rows run); `3d` warps (u, v, unused) the same way
//   in each region's frustum (frustumDirection); `a3` and `sl` hold points (x, y, z) on the
//   screen surface in the file's geometric unit;
// - a NaN sample marks a projector pixel that lands on no screen (shown black), not an error.
#pragma once

#include <rtwall/vec.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rtwall {

enum class MpcdiProfile { Flat2d, Simulation3d, Advanced3d, ShaderLamp };  // "2d", "3d", "a3", "sl"
const char* mpcdiProfileName(MpcdiProfile profile);
// a3 and sl warp to points on the screen surface; 2d to normalised screen coordinates and 3d to
// normalised coordinates in each region's frustum.
inline bool warpsToSurface(MpcdiProfile p) { return p == MpcdiProfile::Advanced3d || p == MpcdiProfile::ShaderLamp; }

// A geometry warp: one sample per grid point, top row first.
struct MpcdiWarp {
    int width = 0, height = 0;
    std::vector<Float3> samples;   // NaN in any component: no screen under that point
    std::string geometricUnit;     // 3D profiles: "mm", "cm", "dm", "m", "in", "ft", "yd" or empty
    double metresPerUnit = 1;      // of geometricUnit (1 when empty or "m")
    size_t validSamples = 0;       // samples without NaN
};

// An alpha (intensity) or beta (black level) map: values in [0, 1], one or three components
// per sample, top row first.
struct MpcdiMap {
    int width = 0, height = 0, components = 1;
    std::vector<float> values;
    double gammaEmbedded = 1;      // alpha maps: the gamma the values were made for (1: linear)
};

// 3D simulation profile: the region's view from the calibration's eye point, degrees. The four
// angles are signed (left and down usually negative) and required; the turns default to 0.
struct MpcdiFrustum {
    double yaw = 0, pitch = 0, roll = 0, leftAngle = 0, rightAngle = 0, upAngle = 0, downAngle = 0;
};
// The direction (not normalised; its component along the frustum's axis is 1) of frustum
// coordinates (u, v), u to the right and v up from the lower left, in the calibration's frame
// (x right, y up, -z forward). The conventions are SGCT's reader's and Christie's
// description of what its tool writes (docs/mpcdi.md): the frustum's image plane spans
// tan(leftAngle)..tan(rightAngle) and tan(downAngle)..tan(upAngle) at distance 1, turned by
// Ry(-yaw) Rx(pitch) Rz(-roll): positive yaw turns right, positive pitch up, positive roll lowers
// the right side.
struct FrustumAxes {
    std::array<double, 3> corner, right, up;  // direction(u, v) = corner + u right + v up
    Float3 direction(double u, double v) const;
};
FrustumAxes frustumAxes(const MpcdiFrustum& frustum);
inline Float3 frustumDirection(const MpcdiFrustum& frustum, double u, double v) { return frustumAxes(frustum).direction(u, v); }

struct MpcdiRegion {
    std::string id;
    int xResolution = 0, yResolution = 0;     // its pixels
    double x = 0, y = 0, xSize = 1, ySize = 1; // where it lies in its buffer, normalised
    std::optional<MpcdiFrustum> frustum;
    MpcdiWarp warp;
    std::optional<MpcdiMap> alpha, beta;
};

struct MpcdiBuffer {
    std::string id;
    int xResolution = 0, yResolution = 0;
    std::vector<MpcdiRegion> regions;
};

struct MpcdiFile {
    std::string version;   // "1.0", "2.0"
    MpcdiProfile profile = MpcdiProfile::Flat2d;
    int level = 1;
    std::vector<MpcdiBuffer> buffers;
    const MpcdiBuffer* buffer(const std::string& id) const;  // null when absent
};

// Limits: no grid or blend map larger than this a side or in all (a map's values counted), no
// archive entry larger than kMaxMpcdiEntry (nothing is allocated for more than what was read).
constexpr int kMaxMpcdiSide = 16384;
constexpr size_t kMaxMpcdiSamples = size_t(64) << 20;
constexpr size_t kMaxMpcdiEntry = size_t(1) << 30;

// Reads a .mpcdi file. Every problem is one InputError line "<file>: <what>", naming the
// archive entry, buffer or region concerned.
MpcdiFile readMpcdi(const std::filesystem::path& file);
MpcdiFile parseMpcdi(std::span<const uint8_t> archive, const std::string& nameForMessages);
// The parts alone (tests, the fuzz target): a PFM geometry warp, and mpcdi.xml with the
// archive's other entries looked up by name (nullopt: no such entry).
MpcdiWarp parsePfm(std::span<const uint8_t> bytes, const std::string& nameForMessages);
using MpcdiEntries = std::function<std::optional<std::vector<uint8_t>>(const std::string& entry)>;
MpcdiFile parseMpcdiXml(std::string_view xml, const MpcdiEntries& entries, const std::string& nameForMessages);

}  // namespace rtwall
