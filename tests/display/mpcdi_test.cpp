// The MPCDI reader (issue 30) on files written by an independent writer (tools/mpcdi_testgen.py,
// Python's zipfile, struct and zlib): a curved three-projector calibration (profile a3), 2D
// identity warps, and broken files, each one clear line naming file and what is wrong.
#include "scratch.h"

#include <rtwall/input_error.h>
#include <rtwall/mpcdi.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

void generate(const std::string& args) { test::mpcdiTestgen(args); }

std::string errorOf(const fs::path& file) {
    try {
        readMpcdi(file);
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

TEST(Mpcdi, CurvedThreeProjectorCalibrationReadsAsWritten) {
    const fs::path dir = test::scratchDir();
    generate("cylinder " + (dir / "cyl.mpcdi").string() + " --res 64x48 --grid 32x24");
    const MpcdiFile f = readMpcdi(dir / "cyl.mpcdi");
    EXPECT_EQ(f.profile, MpcdiProfile::Advanced3d);
    EXPECT_EQ(f.version, "2.0");
    EXPECT_EQ(f.level, 2);
    ASSERT_EQ(f.buffers.size(), 3u);
    for (int k = 0; k < 3; ++k) {
        const MpcdiBuffer& b = f.buffers[size_t(k)];
        SCOPED_TRACE(b.id);
        EXPECT_EQ(b.id, "proj" + std::to_string(k));
        EXPECT_EQ(f.buffer(b.id), &b);
        EXPECT_EQ(b.xResolution, 64);
        EXPECT_EQ(b.yResolution, 48);
        ASSERT_EQ(b.regions.size(), 1u);
        const MpcdiRegion& r = b.regions[0];
        EXPECT_EQ(r.id, b.id + "_region");
        EXPECT_EQ(r.xResolution, 64);
        EXPECT_EQ(r.warp.width, 32);
        EXPECT_EQ(r.warp.height, 24);
        EXPECT_EQ(r.warp.geometricUnit, "m");
        EXPECT_EQ(r.warp.metresPerUnit, 1.0);
        // Every valid sample on the cylinder x^2 + (z - 3)^2 = 9, |y| <= 1.2; the bent corners off it.
        size_t valid = 0;
        for (const Float3& p : r.warp.samples) {
            if (std::isnan(p.x)) continue;
            ++valid;
            EXPECT_NEAR(p.x * p.x + (p.z - 3) * (p.z - 3), 9.0, 1e-4);
            EXPECT_LE(std::abs(p.y), 1.2f);
        }
        EXPECT_EQ(valid, r.warp.validSamples);
        EXPECT_GT(valid, r.warp.samples.size() * 3 / 4);
        EXPECT_LT(valid, r.warp.samples.size()) << "the smile's corners land off the screen";
        // The smile lowers a row's ends: the bottom corners and the top middle land off the screen.
        EXPECT_TRUE(std::isnan(r.warp.samples[size_t(23) * 32].x)) << "bottom left corner";
        EXPECT_TRUE(std::isnan(r.warp.samples.back().x)) << "bottom right corner";
        EXPECT_TRUE(std::isnan(r.warp.samples[16].x)) << "top middle";
        EXPECT_FALSE(std::isnan(r.warp.samples.front().x)) << "top left corner";
        // Top row first: the row above the middle is higher on the screen than the one below.
        const Float3 upper = r.warp.samples[size_t(10) * 32 + 16], lower = r.warp.samples[size_t(13) * 32 + 16];
        EXPECT_GT(upper.y, lower.y);
        // Left to right: the angle grows (x increases across a cylinder seen from inside).
        EXPECT_LT(r.warp.samples[size_t(12) * 32 + 4].x, r.warp.samples[size_t(12) * 32 + 28].x);
        ASSERT_TRUE(r.alpha && r.beta);
        EXPECT_EQ(r.alpha->gammaEmbedded, 2.2);
        EXPECT_EQ(r.beta->gammaEmbedded, 1.0);
        EXPECT_EQ(r.alpha->width, 64);
        EXPECT_EQ(r.alpha->components, 1);
        // The middle projector is fully on in its middle and fades at both sides; the outer ones
        // at their inner side only. Off the screen: no light.
        const auto alphaAt = [&](int x, int y) { return r.alpha->values[size_t(y) * 64 + size_t(x)]; };
        EXPECT_EQ(alphaAt(32, 24), 1.0f);
        EXPECT_EQ(alphaAt(0, 0), 0.0f);
        EXPECT_LT(alphaAt(k == 0 ? 62 : 1, 24), 0.5f);
        if (k != 1) {
            EXPECT_EQ(alphaAt(k == 0 ? 1 : 62, 24), 1.0f);
        }
        EXPECT_NEAR(r.beta->values[size_t(24) * 64 + 32], 0.02f, 0.5f / 255);
    }
    // Neighbours overlap: projector 0's right edge is right of projector 1's left edge.
    const auto& s0 = f.buffers[0].regions[0].warp.samples;
    const auto& s1 = f.buffers[1].regions[0].warp.samples;
    EXPECT_GT(s0[size_t(12) * 32 + 31].x, s1[size_t(12) * 32].x);
}

// Profile 2d: (u, v) from the lower left, pixel centres; rows bottom to top in the PFM. A
// whole-pixel shift moves every sample by exactly that many pixel widths.
TEST(Mpcdi, IdentityAndShiftedTwoDimensionalWarps) {
    const fs::path dir = test::scratchDir();
    generate("identity " + (dir / "id.mpcdi").string() + " --buffer left=40x30 --buffer right=20x10");
    generate("identity " + (dir / "shift.mpcdi").string() + " --buffer left=40x30 --shift 3,-2");
    const MpcdiFile id = readMpcdi(dir / "id.mpcdi"), shift = readMpcdi(dir / "shift.mpcdi");
    EXPECT_EQ(id.profile, MpcdiProfile::Flat2d);
    ASSERT_EQ(id.buffers.size(), 2u);
    ASSERT_NE(id.buffer("right"), nullptr);
    EXPECT_EQ(id.buffer("nope"), nullptr);
    const MpcdiWarp& w = id.buffers[0].regions[0].warp;
    ASSERT_EQ(w.width, 40);
    ASSERT_EQ(w.height, 30);
    EXPECT_EQ(w.validSamples, 1200u);
    EXPECT_FALSE(id.buffers[0].regions[0].alpha.has_value());
    const MpcdiWarp& s = shift.buffers[0].regions[0].warp;
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x) {
            const Float3 p = w.samples[size_t(y) * 40 + size_t(x)], q = s.samples[size_t(y) * 40 + size_t(x)];
            ASSERT_EQ(p.x, float((x + 0.5) / 40)) << x << "," << y;
            ASSERT_EQ(p.y, float(1 - (y + 0.5) / 30)) << x << "," << y;
            ASSERT_EQ(q.x, float((x + 3 + 0.5) / 40));
            ASSERT_EQ(q.y, float(1 - (y - 2 + 0.5) / 30));
        }
}

// Blend maps of 16 bits and of three components (RGB), as other writers export them: every value
// read exactly as written (v / 65535 or v / 255), channel by channel. The values are the writer's
// (tools/mpcdi_testgen.py map_values): distinct for every pixel and channel.
TEST(Mpcdi, SixteenBitAndRgbBlendMapsReadAsWritten) {
    const fs::path dir = test::scratchDir();
    auto expected = [](int n, bool alpha, int bits) {
        std::vector<float> v;
        const double top = bits == 16 ? 65535.0 : 255.0;
        for (int k = 0; k < n; ++k) {
            const double x = alpha ? double((k * 997 + 13) % 65536) / 65535.0 : double(k % 23) / 22.0;
            v.push_back(float(std::round(x * top)) / float(top));  // as the writer quantises and the reader scales
        }
        return v;
    };
    struct Case {
        int alphaChannels, alphaBits, betaChannels, betaBits;
    };
    for (const Case c : {Case{1, 16, 3, 8}, Case{3, 16, 1, 16}, Case{3, 8, 3, 16}}) {
        const std::string name = std::to_string(c.alphaChannels) + "x" + std::to_string(c.alphaBits) + "_" +
                                 std::to_string(c.betaChannels) + "x" + std::to_string(c.betaBits);
        const fs::path file = dir / (name + ".mpcdi");
        generate("depths " + file.string() + " --alpha " + std::to_string(c.alphaChannels) + "x" + std::to_string(c.alphaBits) +
                 " --beta " + std::to_string(c.betaChannels) + "x" + std::to_string(c.betaBits));
        const MpcdiFile f = readMpcdi(file);
        ASSERT_EQ(f.buffers.size(), 1u) << name;
        const MpcdiRegion& r = f.buffers[0].regions.at(0);
        ASSERT_TRUE(r.alpha && r.beta) << name;
        EXPECT_EQ(r.alpha->components, c.alphaChannels) << name;
        EXPECT_EQ(r.beta->components, c.betaChannels) << name;
        EXPECT_EQ(r.alpha->gammaEmbedded, 1.0) << name;
        EXPECT_EQ(r.alpha->width, 6);
        EXPECT_EQ(r.alpha->height, 4);
        EXPECT_EQ(r.alpha->values, expected(6 * 4 * c.alphaChannels, true, c.alphaBits)) << name;
        EXPECT_EQ(r.beta->values, expected(6 * 4 * c.betaChannels, false, c.betaBits)) << name;
    }
}

// What writers differ in: attribute and element case, filesets inside their region, a path as
// the element's own text, an unnamed buffer, millimetres.
TEST(Mpcdi, WritersSpellingsAreRead) {
    std::string pfm = "PF\n2 1\n1.0\n";  // positive scale: big-endian
    for (float v : {1.f, 2.f, 3.f, 4.f, 5.f, 6.f}) {
        uint8_t b[4];
        std::memcpy(b, &v, 4);
        pfm += std::string{char(b[3]), char(b[2]), char(b[1]), char(b[0])};
    }
    const std::map<std::string, std::string> entries{{"w.pfm", pfm}};
    const MpcdiEntries lookup = [&](const std::string& name) -> std::optional<std::vector<uint8_t>> {
        const auto it = entries.find(name);
        if (it == entries.end()) return std::nullopt;
        return std::vector<uint8_t>(it->second.begin(), it->second.end());
    };
    const std::string xml = R"(<?xml version="1.0"?>
<mpcdi Profile="A3" version="1.0">
  <Display>
    <buffer xResolution="2" yResolution="1">
      <region id="r" xResolution="2" YRESOLUTION="1">
        <fileSet><GeometryWarpFile>w.pfm<geometricUnit>mm</geometricUnit></GeometryWarpFile></fileSet>
      </region>
    </buffer>
  </Display>
</mpcdi>)";
    const MpcdiFile f = parseMpcdiXml(xml, lookup, "spell.mpcdi");
    EXPECT_EQ(f.profile, MpcdiProfile::Advanced3d);
    ASSERT_EQ(f.buffers.size(), 1u);
    EXPECT_EQ(f.buffers[0].id, "buffer0");
    const MpcdiWarp& w = f.buffers[0].regions[0].warp;
    EXPECT_EQ(w.metresPerUnit, 0.001);
    ASSERT_EQ(w.samples.size(), 2u);
    EXPECT_EQ(w.samples[0], (Float3{1, 2, 3}));
    EXPECT_EQ(w.samples[1], (Float3{4, 5, 6}));
}

TEST(Mpcdi, BadFilesAreOneLineNamingFileAndWhat) {
    const fs::path dir = test::scratchDir();
    generate("malformed " + dir.string());
    EXPECT_EQ(readMpcdi(dir / "good.mpcdi").buffers.size(), 1u);
    const std::map<std::string, std::string> expected{
        {"truncated-zip.mpcdi", "not a readable zip archive"},
        {"not-a-zip.mpcdi", "not a readable zip archive"},
        {"no-mpcdi-xml.mpcdi", "the archive has no mpcdi.xml"},
        {"missing-warp.mpcdi", "region 'r0' geometry warp 'r0.pfm' is not in the archive"},
        {"no-geometry-warp.mpcdi", "region 'r0' has no geometryWarpFile"},
        {"pfm-short.mpcdi", "r0.pfm: PFM header says 8x6 (576 bytes of samples) but the file holds 564"},
        {"pfm-huge-header.mpcdi", "r0.pfm: PFM header: 16384x16384 samples, more than 67108864"},
        {"pfm-infinite.mpcdi", "r0.pfm: sample (3, 2) from the top left is infinite"},
        {"all-nan.mpcdi", "region 'r0' geometry warp 'r0.pfm': every sample is NaN"},
        {"alpha-wrong-size.mpcdi", "r0_alpha.png: a blend map of 9x6, its region has 8x6 pixels"},
        {"unknown-profile.mpcdi", "profile '4d' is none of 2d, 3d, a3, sl"},
        {"bad-xml.mpcdi", "mpcdi.xml at byte"},
        {"pfm-one-component.mpcdi", "a one-component PFM (Pf)"},
        {"alpha-huge.mpcdi", "r0_alpha.png: a blend map of 8200x8192x1 values, more than 67108864"},
        {"3d-no-frustum.mpcdi", "region 'r0' has no <frustum> (profile 3d: its warp holds coordinates in that frustum)"},
        {"3d-no-left-angle.mpcdi", "region 'r0' frustum has no leftAngle"},
        {"3d-empty-frustum.mpcdi", "region 'r0' frustum: its angles span no view (left < right, down < up, each between -90 and 90 degrees)"},
    };
    for (const auto& [name, what] : expected) {
        SCOPED_TRACE(name);
        const std::string e = errorOf(dir / name);
        EXPECT_EQ(e.rfind((dir / name).string() + ": ", 0), 0u) << e;
        EXPECT_NE(e.find(what), std::string::npos) << e;
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    }
    EXPECT_NE(errorOf(dir / "absent.mpcdi").find("absent.mpcdi: cannot read it"), std::string::npos);
}

// Names from the file go into messages quoted, control bytes as \xNN, at most 64 bytes of them
// (fuzz_mpcdi found a two-line error: tests/fuzz/crashes/mpcdi).
TEST(Mpcdi, NamesFromTheFileCannotBreakTheErrorLine) {
    const MpcdiEntries none = [](const std::string&) { return std::nullopt; };
    auto error = [&](const std::string& xml) {
        try {
            parseMpcdiXml(xml, none, "x.mpcdi");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("(no error)");
    };
    const std::string region = R"(<MPCDI profile="2d"><display><buffer Xresolution="2" Yresolution="2"><region id="r0" )"
                               R"(Xresolution="2" Yresolution="2"><fileset><geometryWarpFile><path>)";
    EXPECT_EQ(error(region + "r0.\npfm</path></geometryWarpFile></fileset></region></buffer></display></MPCDI>"),
              "x.mpcdi: region 'r0' geometry warp 'r0.\\x0apfm' is not in the archive");
    EXPECT_EQ(error(region + std::string(100, 'a') + "</path></geometryWarpFile></fileset></region></buffer></display></MPCDI>"),
              "x.mpcdi: region 'r0' geometry warp '" + std::string(64, 'a') + "...' is not in the archive");
    EXPECT_EQ(error(R"(<MPCDI profile="2d"><display><buffer Xresolution="2" Yresolution="2"/></display></MPCDI>)"),
              "x.mpcdi: buffer 'buffer0' has no region");
    EXPECT_EQ(error(R"(<MPCDI profile="2d"><display><buffer Xresolution="0" Yresolution="2"/></display></MPCDI>)"),
              "x.mpcdi: buffer 'buffer0' Xresolution is 0 (a whole number of pixels, 1 to 16384)");
}

TEST(Mpcdi, PfmHeadersAreCheckedBeforeAnySampleIsRead) {
    auto error = [](const std::string& bytes) {
        try {
            parsePfm(std::span(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()), "w.pfm");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("(no error)");
    };
    EXPECT_EQ(error("PF\n16384 16384\n-1.0\n"), "w.pfm: PFM header: 16384x16384 samples, more than 67108864");
    EXPECT_EQ(error("PF\n4096 4096\n-1.0\n"), "w.pfm: PFM header says 4096x4096 (201326592 bytes of samples) but the file holds 0");
    EXPECT_EQ(error("PF\n-3 2\n-1.0\n"), "w.pfm: PFM header: width '-3' is not a whole number from 1 to 16384");
    EXPECT_EQ(error("PF\n3 99999999999\n-1.0\n"),
              "w.pfm: PFM header: height '99999999999' is not a whole number from 1 to 16384");
    EXPECT_EQ(error("PF\n1 1\n0\n"), "w.pfm: PFM header: scale '0' is not a non-zero number");
    EXPECT_EQ(error("PF\n1 1\nnan\n"), "w.pfm: PFM header: scale 'nan' is not a non-zero number");
    EXPECT_EQ(error("PF\n1 1\n-1.0"), "w.pfm: PFM header: no samples after it");
    EXPECT_EQ(error("P6\n1 1\n255\n"), "w.pfm: not a PFM file (it does not start with PF)");
    EXPECT_EQ(error(""), "w.pfm: not a PFM file (it does not start with PF)");
    EXPECT_EQ(error("PF\n1 1\n-1.0\n" + std::string(13, '\0')),
              "w.pfm: PFM header says 1x1 (12 bytes of samples) but the file holds 13");
    EXPECT_EQ(error("PF\n1 1\n-1.0\n" + std::string(12, '\0')), "(no error)");
}

// The frustum's turns and angles, pinned by their documented meaning (SGCT's reading,
// Christie's description): positive yaw turns the view right (+x), positive pitch up (+y),
// positive roll lowers the right side; the angles are signed and bound the image plane at
// tan(angle) one unit along the axis; (u, v) run right and up from the lower left.
TEST(Mpcdi, FrustumDirectionsFollowTheDocumentedTurns) {
    auto near = [](Float3 a, Float3 b) { return std::abs(a.x - b.x) < 1e-6f && std::abs(a.y - b.y) < 1e-6f && std::abs(a.z - b.z) < 1e-6f; };
    MpcdiFrustum f{.leftAngle = -45, .rightAngle = 45, .upAngle = 45, .downAngle = -45};
    EXPECT_TRUE(near(frustumDirection(f, 0.5, 0.5), {0, 0, -1}));
    EXPECT_TRUE(near(frustumDirection(f, 1, 0.5), {1, 0, -1}));   // u to the right
    EXPECT_TRUE(near(frustumDirection(f, 0.5, 1), {0, 1, -1}));   // v up
    EXPECT_TRUE(near(frustumDirection(f, 0, 0), {-1, -1, -1}));   // the lower left
    MpcdiFrustum yawed = f;
    yawed.yaw = 90;
    EXPECT_TRUE(near(frustumDirection(yawed, 0.5, 0.5), {1, 0, 0}));
    EXPECT_TRUE(near(frustumDirection(yawed, 1, 0.5), {1, 0, 1}));  // its right is the room's +z now
    MpcdiFrustum pitched = f;
    pitched.pitch = 90;
    EXPECT_TRUE(near(frustumDirection(pitched, 0.5, 0.5), {0, 1, 0}));
    MpcdiFrustum rolled = f;
    rolled.roll = 90;
    EXPECT_TRUE(near(frustumDirection(rolled, 1, 0.5), {0, -1, -1}));  // the right side lowered
    MpcdiFrustum offAxis{.leftAngle = -10, .rightAngle = 30, .upAngle = 20, .downAngle = -5};
    const Float3 d = frustumDirection(offAxis, 0, 1);
    EXPECT_NEAR(d.x, std::tan(-10 * 3.14159265358979 / 180), 1e-6);
    EXPECT_NEAR(d.y, std::tan(20 * 3.14159265358979 / 180), 1e-6);
}

}  // namespace
}  // namespace rtwall
