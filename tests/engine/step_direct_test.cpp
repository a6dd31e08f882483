// Issue 29, linear cold import: rtwall reads a STEP file's product structure itself
// (mesh/src/import_step_direct.cpp) and has OCCT transfer only the distinct parts, where OCCT's
// XDE transfer grows as the square of the occurrences. The assembly must be the one XDE gives:
// the same meshes (bit for bit), parts, names, colours and placements, on every kind of file
// `rtwall gen` writes (declared reuse, nested rows, flat, curved parts, other length units); a
// file with what only XDE reads falls back to XDE and says why.
#include "step_assembly.h"
#include "test_util.h"

#include "generators.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

Assembly load(const fs::path& file, bool throughXde) {
    AssemblyOptions o;
    o.stepThroughXde = throughXde;
    return loadAssembly(file, o);
}

// Everything the rest of rtwall sees of an assembly, compared exactly.
void expectSameAssembly(const Assembly& a, const Assembly& b) {
    ASSERT_EQ(a.meshes.size(), b.meshes.size());
    EXPECT_EQ(a.meshNames, b.meshNames);
    for (size_t m = 0; m < a.meshes.size(); ++m) {
        const TriangleMesh &x = *a.meshes[m], &y = *b.meshes[m];
        ASSERT_EQ(x.vertexCount(), y.vertexCount()) << m;
        ASSERT_EQ(x.triangleCount(), y.triangleCount()) << m;
        EXPECT_EQ(0, std::memcmp(x.positions(), y.positions(), 12 * x.vertexCount())) << m;
        EXPECT_EQ(0, std::memcmp(x.normals(), y.normals(), 12 * x.vertexCount())) << m;
        EXPECT_EQ(0, std::memcmp(x.indices(), y.indices(), 12 * x.triangleCount())) << m;
        EXPECT_EQ(x.origin(), y.origin()) << m;
    }
    ASSERT_EQ(a.parts.size(), b.parts.size());
    for (size_t i = 0; i < a.parts.size(); ++i) {
        EXPECT_EQ(a.parts[i].name, b.parts[i].name) << i;
        EXPECT_EQ(a.parts[i].parent, b.parts[i].parent) << i;
    }
    ASSERT_EQ(a.materials.size(), b.materials.size());
    for (size_t i = 0; i < a.materials.size(); ++i) {
        EXPECT_EQ(a.materials[i].name, b.materials[i].name);
        EXPECT_EQ(a.materials[i].baseColor, b.materials[i].baseColor);
    }
    ASSERT_EQ(a.instances.size(), b.instances.size());
    for (size_t i = 0; i < a.instances.size(); ++i) {
        EXPECT_EQ(a.instances[i].mesh, b.instances[i].mesh) << i;
        EXPECT_EQ(a.instances[i].material, b.instances[i].material) << i;
        EXPECT_EQ(a.instances[i].part, b.instances[i].part) << i;
        EXPECT_EQ(a.instances[i].transform, b.instances[i].transform) << i;
    }
    EXPECT_EQ(a.warnings, b.warnings);
    EXPECT_EQ(a.congruentMeshes, b.congruentMeshes);
}

void expectDirectMatchesXde(const fs::path& file) {
    SCOPED_TRACE(file.string());
    const Assembly direct = load(file, false), xde = load(file, true);
    EXPECT_EQ(direct.reader, "direct");
    EXPECT_EQ(xde.reader, "xde: asked for (AssemblyOptions::stepThroughXde)");
    ASSERT_FALSE(direct.instances.empty());
    expectSameAssembly(direct, xde);
}

TEST(StepDirect, SameAssemblyAsXdeOnEveryKindOfFile) {
    expectDirectMatchesXde(test::stepAssembly());  // 3 modules of 7: names, colours
    const auto dir = test::scratchDir();
    gen::genStep({.out = dir / "rows", .instances = 40, .rows = true});
    expectDirectMatchesXde(dir / "rows" / "assembly.step");
    gen::genStep({.out = dir / "flat", .instances = 14, .flat = true});  // free solids, a mirrored one
    expectDirectMatchesXde(dir / "flat" / "assembly.step");
    gen::genStepCurved({.out = dir / "curved", .instances = 11});  // fillets, tori, spheres
    expectDirectMatchesXde(dir / "curved" / "assembly.step");
}

// Placements in metres and inches: the representation's units scale the axis placements as OCCT
// scales them, and the parts land where the millimetre file puts them.
TEST(StepDirect, LengthUnitsScalePlacements) {
    const auto dir = test::scratchDir();
    const Assembly mm = load(test::stepAssembly(), false);
    for (const char* unit : {"M", "INCH"}) {
        SCOPED_TRACE(unit);
        gen::genStep({.out = dir / unit, .instances = 21, .stepUnit = unit});
        const fs::path file = dir / unit / "assembly.step";
        std::ifstream in(file);
        std::stringstream text;
        text << in.rdbuf();
        EXPECT_NE(text.str().find(std::string(unit) == "M" ? "SI_UNIT($,.METRE.)" : "'INCH'"), std::string::npos)
            << "the file is not in " << unit;
        expectDirectMatchesXde(file);
        // Against the millimetre file: the same tree and placements (an inch file's rounded
        // coordinates may tessellate a little differently, so the meshes are not compared).
        const Assembly a = load(file, false);
        ASSERT_EQ(a.parts.size(), mm.parts.size());
        for (size_t i = 0; i < a.parts.size(); ++i) EXPECT_EQ(a.parts[i].name, mm.parts[i].name);
        ASSERT_EQ(a.instances.size(), mm.instances.size());
        for (size_t i = 0; i < a.instances.size(); ++i)
            for (size_t k = 0; k < 12; ++k)
                EXPECT_NEAR(a.instances[i].transform[k], mm.instances[i].transform[k], 1e-3) << i << " " << k << ": within a micrometre";
    }
}

// Placements written the other way round (the relationship's first representation the
// assembly's, its transformation's items swapped, as some writers do): OCCT inverts the
// transformation; so does the direct reader, and the parts land where they did.
TEST(StepDirect, ReversedRelationshipsPlaceTheSame) {
    std::ifstream in(test::stepAssembly());
    std::stringstream text;
    text << in.rdbuf();
    std::string s = std::regex_replace(
        text.str(), std::regex(R"(REPRESENTATION_RELATIONSHIP\('([^']*)','([^']*)',(#\d+),(#\d+)\)(\s*REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION))"),
        "REPRESENTATION_RELATIONSHIP('$1','$2',$4,$3)$5");
    s = std::regex_replace(s, std::regex(R"(ITEM_DEFINED_TRANSFORMATION\('([^']*)','([^']*)',(#\d+),(#\d+)\))"),
                           "ITEM_DEFINED_TRANSFORMATION('$1','$2',$4,$3)");
    ASSERT_NE(s, text.str());
    const fs::path file = test::scratchDir() / "reversed.step";
    std::ofstream(file) << s;
    expectDirectMatchesXde(file);
    const Assembly reversed = load(file, false), plain = load(test::stepAssembly(), false);
    ASSERT_EQ(reversed.instances.size(), plain.instances.size());
    for (size_t i = 0; i < plain.instances.size(); ++i)
        for (size_t k = 0; k < 12; ++k)
            EXPECT_NEAR(reversed.instances[i].transform[k], plain.instances[i].transform[k], 1e-9) << i << " " << k;
}

// Names outside ASCII (UTF-8 in the file, as CAD tools write German or Japanese part names) come
// out as XDE's document gives them, and both give them in UTF-8, as written (before, XDE's names
// came through Latin-1 with '?' for the rest: "Schraube \xD8" "8 ???", not valid UTF-8).
TEST(StepDirect, NamesOutsideAsciiAreXdesNames) {
    std::ifstream in(test::stepAssembly());
    std::stringstream text;
    text << in.rdbuf();
    std::string s = std::regex_replace(text.str(), std::regex("'bolt'"), "'Schraube \xC3\x98" "8 \xE3\x83\x9C\xE3\x83\xAB\xE3\x83\x88'");
    ASSERT_NE(s, text.str());
    const fs::path file = test::scratchDir() / "names.step";
    std::ofstream(file) << s;
    expectDirectMatchesXde(file);
    const Assembly a = load(file, false);
    EXPECT_NE(std::find(a.meshNames.begin(), a.meshNames.end(), "Schraube \xC3\x98" "8 \xE3\x83\x9C\xE3\x83\xAB\xE3\x83\x88"),
              a.meshNames.end());
}

// A construct only XDE reads (here an overriding style: component colours) sends the file
// through XDE, which says so; the result is still the file's.
// The same file with an overriding twin of its first style (component colours: only XDE reads
// them).
std::string withOverridingStyle(const fs::path& file) {
    std::ifstream in(file);
    std::stringstream text;
    text << in.rdbuf();
    std::string s = text.str();
    std::smatch m;
    if (!std::regex_search(s, m, std::regex(R"(#(\d+) ?= ?STYLED_ITEM\(('[^']*'),\((#\d+)\),(#\d+)\) ?;)"))) return {};
    const std::string twin = "#9999999=OVER_RIDING_STYLED_ITEM(" + m[2].str() + ",(" + m[3].str() + ")," + m[4].str() + ",#" +
                             m[1].str() + ");\n";
    const size_t end = s.find("ENDSEC;", size_t(m.position(0)));
    if (end == std::string::npos) return {};
    s.insert(end, twin);
    return s;
}

TEST(StepDirect, WhatOnlyXdeReadsFallsBackToXde) {
    const std::string s = withOverridingStyle(test::stepAssembly());
    ASSERT_FALSE(s.empty());
    const fs::path file = test::scratchDir() / "overriding.step";
    std::ofstream(file) << s;
    const Assembly a = load(file, false);
    EXPECT_EQ(a.reader, "xde: overriding styles (component colours)");
    expectSameAssembly(a, load(file, true));
    EXPECT_EQ(a.instances.size(), 21u);
    EXPECT_TRUE(a.warnings.empty()) << "10 occurrences: XDE is quick there";
}

// A large file that must go through XDE says so, and why, in one warning line.
TEST(StepDirect, ALargeFileThatFallsBackToXdeSaysWhy) {
    const auto dir = test::scratchDir();
    gen::genStep({.out = dir, .instances = 9100});  // 1,300 modules of 7: 1,307 occurrences (NAUOs)
    const std::string s = withOverridingStyle(dir / "assembly.step");
    ASSERT_FALSE(s.empty());
    std::ofstream(dir / "overriding.step") << s;
    AssemblyOptions o;
    o.shareCongruent = false;
    const Assembly a = loadAssembly(dir / "overriding.step", o);
    EXPECT_EQ(a.reader, "xde: overriding styles (component colours)");
    ASSERT_EQ(a.warnings.size(), 1u);
    EXPECT_NE(a.warnings[0].find("overriding.step: read through OpenCASCADE's XDE document, whose import time grows as the square of "
                                 "its 1307 assembly occurrences"),
              std::string::npos) << a.warnings[0];
    EXPECT_NE(a.warnings[0].find("because the file has overriding styles (component colours)"), std::string::npos) << a.warnings[0];
}

}  // namespace
}  // namespace rtwall
