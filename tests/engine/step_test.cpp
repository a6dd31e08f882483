// STEP assemblies (issue 20): a file written through OpenCASCADE's XDE writer by `rtwall gen step`
// (tools/gen/step_assembly.cpp), read back through the XDE reader: each distinct part tessellated
// once, placed by as many instances as the assembly uses it, with names, colours and transforms;
// the tessellation deflections control the triangle count; bad files are one-line errors.
#include "step_assembly.h"
#include "test_util.h"

#include "generators.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

const fs::path& stepFile() { return test::stepAssembly(); }  // 21 instances of 3 parts

// The same instances: meshes, materials, parts and transforms.
void expectSameInstances(const Assembly& a, const Assembly& b) {
    ASSERT_EQ(a.instances.size(), b.instances.size());
    for (size_t i = 0; i < a.instances.size(); ++i) {
        EXPECT_EQ(a.instances[i].mesh, b.instances[i].mesh);
        EXPECT_EQ(a.instances[i].material, b.instances[i].material);
        EXPECT_EQ(a.instances[i].part, b.instances[i].part);
        EXPECT_EQ(a.instances[i].transform, b.instances[i].transform);
    }
}

std::array<double, 3> centre(const Assembly& a, const AssemblyInstance& in) {
    const Bounds3 b = a.meshes[in.mesh]->bounds();
    const double p[3] = {0.5 * (b.lo.x + b.hi.x), 0.5 * (b.lo.y + b.hi.y), 0.5 * (b.lo.z + b.hi.z)};
    const auto& m = in.transform;
    return {m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3], m[4] * p[0] + m[5] * p[1] + m[6] * p[2] + m[7],
            m[8] * p[0] + m[9] * p[1] + m[10] * p[2] + m[11]};
}

TEST(Step, UniquePartsTessellatedOnceAndInstanced) {
    const Assembly a = loadAssembly(stepFile());
    EXPECT_EQ(a.format, "step");
    ASSERT_EQ(a.meshes.size(), 3u) << "plate, bolt, bracket: each tessellated once";
    std::vector<std::string> names = a.meshNames;
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"bolt", "bracket", "plate"}));
    ASSERT_EQ(a.instances.size(), 21u);
    for (const auto& m : a.meshes) {
        EXPECT_GT(m->triangleCount(), 10u);
        EXPECT_TRUE(m->hasNormals());
    }
    size_t bolts = 0;
    for (const AssemblyInstance& in : a.instances) bolts += a.meshNames[in.mesh] == "bolt";
    EXPECT_EQ(bolts, 12u);

    // The tree: plant > module N > its seven components.
    ASSERT_FALSE(a.parts.empty());
    EXPECT_EQ(a.parts[0].name, "plant");
    EXPECT_EQ(a.parts[0].parent, -1);
    size_t modules = 0;
    for (const AssemblyPart& p : a.parts) modules += p.name.rfind("module ", 0) == 0 && p.parent == 0;
    EXPECT_EQ(modules, 3u);

    // Colours: the bolts' (0.8, 0.65, 0.2), through the file's colour entities.
    for (const AssemblyInstance& in : a.instances) {
        if (a.meshNames[in.mesh] != "bolt") continue;
        const auto& c = a.materials[in.material].baseColor;
        EXPECT_NEAR(c[0], 0.8, 0.01);
        EXPECT_NEAR(c[1], 0.65, 0.01);
        EXPECT_NEAR(c[2], 0.2, 0.01);
    }

    // Transforms: module m lies at (100 (m mod 2), 100 (m div 2)) in the file's z-up frame, turned
    // m x 90 degrees; rtwall turns z-up into y-up: (x, y, z) -> (x, z, -y). The plate is centred
    // on its module, 3 mm up.
    std::vector<std::array<double, 3>> plates;
    for (const AssemblyInstance& in : a.instances)
        if (a.meshNames[in.mesh] == "plate") plates.push_back(centre(a, in));
    ASSERT_EQ(plates.size(), 3u);
    const std::array<double, 3> want[3] = {{0, 3, 0}, {100, 3, 0}, {0, 3, -100}};
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(plates[size_t(i)][size_t(k)], want[i][size_t(k)], 1e-3) << i << " " << k;
    const SceneDesc d = sceneFromMeshFile(stepFile());
    EXPECT_EQ(d.instances.size(), 21u);
    EXPECT_EQ(d.meshes.size(), 3u);
    const std::string path = d.partPath(d.instances.back().part);
    EXPECT_EQ(path.rfind("plant/module ", 0), 0u) << path;
}

TEST(Step, DeflectionControlsTheTessellation) {
    AssemblyOptions coarse, fine;
    coarse.linearDeflection = 1.0;
    fine.linearDeflection = 0.01;
    fine.angularDeflection = 0.1;
    const Assembly c = loadAssembly(stepFile(), coarse), f = loadAssembly(stepFile(), fine);
    auto boltTriangles = [](const Assembly& a) {
        for (size_t i = 0; i < a.meshes.size(); ++i)
            if (a.meshNames[i] == "bolt") return a.meshes[i]->triangleCount();
        return size_t(0);
    };
    EXPECT_GT(boltTriangles(f), 4 * boltTriangles(c));
    AssemblyOptions bad;
    bad.linearDeflection = 0;
    EXPECT_NE(test::inputErrorOf([&] { loadAssembly(stepFile(), bad); }).find("deflections must be positive"), std::string::npos);
}

// The assembly cache: a second load maps the tessellated parts from FILE.rtwasm and gives the
// same assembly; the key is the file's content (a rewrite with the same bytes still hits) and the
// deflections; a changed file or a corrupt cache is rebuilt, never trusted.
TEST(Step, CacheIsKeyedByContentAndDeflections) {
    const fs::path dir = test::scratchDir();
    const fs::path file = dir / "a.step";
    fs::copy_file(stepFile(), file);
    AssemblyOptions o;
    o.cache = true;
    const Assembly first = loadAssembly(file, o);
    EXPECT_EQ(first.cache, "written");
    ASSERT_TRUE(fs::exists(dir / "a.step.rtwasm"));
    const Assembly hit = loadAssembly(file, o);
    EXPECT_EQ(hit.cache, "hit");
    ASSERT_EQ(hit.meshes.size(), first.meshes.size());
    EXPECT_EQ(hit.meshNames, first.meshNames);
    ASSERT_NO_FATAL_FAILURE(expectSameInstances(hit, first));
    ASSERT_EQ(hit.parts.size(), first.parts.size());
    for (size_t i = 0; i < hit.parts.size(); ++i) {
        EXPECT_EQ(hit.parts[i].name, first.parts[i].name);
        EXPECT_EQ(hit.parts[i].parent, first.parts[i].parent);
    }
    ASSERT_EQ(hit.materials.size(), first.materials.size());
    for (size_t i = 0; i < hit.materials.size(); ++i) EXPECT_EQ(hit.materials[i].baseColor, first.materials[i].baseColor);
    for (size_t m = 0; m < hit.meshes.size(); ++m) {
        EXPECT_TRUE(hit.meshes[m]->isMapped()) << "rendered where the cache file lies";
        ASSERT_EQ(hit.meshes[m]->vertexCount(), first.meshes[m]->vertexCount());
        ASSERT_EQ(hit.meshes[m]->triangleCount(), first.meshes[m]->triangleCount());
        EXPECT_EQ(0, std::memcmp(hit.meshes[m]->positions(), first.meshes[m]->positions(), 12 * first.meshes[m]->vertexCount()));
        EXPECT_EQ(0, std::memcmp(hit.meshes[m]->indices(), first.meshes[m]->indices(), 12 * first.meshes[m]->triangleCount()));
        EXPECT_EQ(hit.meshes[m]->origin(), first.meshes[m]->origin());
    }

    // The same bytes written again (a new modification time): still a hit.
    {
        std::ifstream in(file, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        in.close();
        test::writeFile(file, bytes);
        EXPECT_EQ(loadAssembly(file, o).cache, "hit");
        // Other deflections: rebuilt.
        AssemblyOptions finer = o;
        finer.linearDeflection = 0.05;
        EXPECT_NE(loadAssembly(file, finer).cache.find("rebuilt: "), std::string::npos);
        EXPECT_NE(loadAssembly(file, o).cache.find("deflections"), std::string::npos);
        // Another content (a comment line added at the end): rebuilt as stale.
        test::writeFile(file, bytes + "/* edited */\n");
        const Assembly edited = loadAssembly(file, o);
        EXPECT_NE(edited.cache.find("stale"), std::string::npos) << edited.cache;
        EXPECT_EQ(edited.instances.size(), 21u);
    }
    // A flipped byte in a cached mesh: the checksum catches it and the cache is rebuilt.
    EXPECT_EQ(loadAssembly(file, o).cache, "hit");
    {
        std::fstream f(dir / "a.step.rtwasm", std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(-64, std::ios::end);
        f.put('\x5a');
    }
    const Assembly rebuilt = loadAssembly(file, o);
    EXPECT_NE(rebuilt.cache.find("checksum"), std::string::npos) << rebuilt.cache;
    EXPECT_EQ(rebuilt.instances.size(), 21u);
}

// The same assembly written as IGES (IGESCAFControl_Writer) and read through the IGES reader.
// OCCT's IGES writer flattens the assembly into one named compound, so what comes back is one
// part holding all 21 placed parts' surfaces: at least 3 x (plate + 4 bolts + 2 brackets).
TEST(Step, IgesAssemblyReads) {
    const auto dir = test::scratchDir();
    gen::genIges({.out = dir, .instances = 21});
    const Assembly a = loadAssembly(dir / "assembly.igs");
    EXPECT_EQ(a.format, "iges");
    ASSERT_FALSE(a.instances.empty());
    size_t triangles = 0;
    for (const AssemblyInstance& in : a.instances) triangles += a.meshes[in.mesh]->triangleCount();
    const Assembly step = loadAssembly(stepFile());
    size_t stepTriangles = 0;
    for (const AssemblyInstance& in : step.instances) stepTriangles += step.meshes[in.mesh]->triangleCount();
    EXPECT_GE(triangles, stepTriangles * 9 / 10);
    EXPECT_LE(triangles, stepTriangles * 11 / 10);
    EXPECT_EQ(a.parts.at(0).name, "plant");
    EXPECT_NE(test::inputErrorOf([&] { loadAssembly(test::writeFile(dir / "bad.igs", "not IGES\n")); }).find("bad.igs: "), std::string::npos);
}

// Progress reaches 1 through the transfer and the tessellation, and a progress function that
// says stop makes the load throw Cancelled (what Ctrl-C does), in either phase.
TEST(Step, ProgressAndCancel) {
    std::vector<double> seen;
    AssemblyOptions o;
    o.progress = [&](double f) {
        seen.push_back(f);
        return true;
    };
    loadAssembly(stepFile(), o);
    ASSERT_GE(seen.size(), 4u);
    EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
    EXPECT_DOUBLE_EQ(seen.back(), 1.0);
    EXPECT_GT(std::count_if(seen.begin(), seen.end(), [](double f) { return f > 0.0 && f < 0.9; }), 0) << "the transfer reports";
    for (double stopAt : {0.0, 0.95}) {
        AssemblyOptions c;
        c.progress = [&](double f) { return f < stopAt; };
        EXPECT_THROW(loadAssembly(stepFile(), c), Cancelled) << stopAt;
    }
}

// gen step --rows nests the same modules in row sub-assemblies: plant > row N > module M > part;
// the parts land where the flat file puts them.
TEST(Step, RowsNestTheSameModules) {
    const auto dir = test::scratchDir();
    gen::genStep({.out = dir, .instances = 21, .rows = true});
    const Assembly rows = loadAssembly(dir / "assembly.step"), flat = loadAssembly(stepFile());
    ASSERT_EQ(rows.instances.size(), 21u);
    EXPECT_EQ(rows.parts.at(0).name, "plant");
    std::vector<std::string> rowNames;
    for (const AssemblyPart& p : rows.parts)
        if (p.parent == 0) rowNames.push_back(p.name);
    EXPECT_EQ(rowNames, (std::vector<std::string>{"row 1", "row 2"}));  // 3 modules, 2 a row
    for (const AssemblyInstance& in : rows.instances) {
        const int32_t module = rows.parts[in.part].parent;
        ASSERT_GE(module, 0);
        EXPECT_EQ(rows.parts[size_t(module)].name.rfind("module ", 0), 0u);
        EXPECT_EQ(rows.parts[size_t(rows.parts[size_t(module)].parent)].name.rfind("row ", 0), 0u);
    }
    auto centres = [](const Assembly& a) {
        std::vector<std::array<long, 3>> c;
        for (const AssemblyInstance& in : a.instances) {
            const auto p = centre(a, in);
            c.push_back({std::lround(p[0] * 1000), std::lround(p[1] * 1000), std::lround(p[2] * 1000)});
        }
        std::sort(c.begin(), c.end());
        return c;
    };
    EXPECT_EQ(centres(rows), centres(flat));
}

// Issue 29: a flat STEP file (every part a solid of its own, placed in its geometry) of 3
// modules, 21 solids that are 3 shapes, and a mirrored bracket: the 3 shapes are stored once;
// the bracket is a box, which a mirror maps onto itself turned, so its mirror image (OCCT
// mirrors the faces' orientation too, and numbers the vertices otherwise) is the bracket again
// and is found as well (chiral shapes' mirror images stay apart: Gltf.CongruentShapesAreStoredOnce).
// Every part lands where the file puts it, as in the assembly that declares its reuse.
TEST(Step, FlatFileCongruentSolidsAreStoredOnce) {
    const auto dir = test::scratchDir();
    gen::genStep({.out = dir, .instances = 21, .flat = true});
    AssemblyOptions off;
    off.shareCongruent = false;
    const Assembly flat = loadAssembly(dir / "assembly.step", off);
    const Assembly found = loadAssembly(dir / "assembly.step");
    ASSERT_EQ(flat.instances.size(), 22u);
    EXPECT_EQ(flat.meshes.size(), 22u);
    EXPECT_EQ(found.meshes.size(), 3u);  // plate, bolt, bracket (the mirrored bracket is a bracket)
    EXPECT_EQ(found.congruentMeshes, 19u);
    ASSERT_EQ(found.instances.size(), 22u);
    size_t mirroredMesh = SIZE_MAX, uses = 0;
    for (const AssemblyInstance& in : found.instances)
        if (found.parts[in.part].name == "bracket mirrored") mirroredMesh = in.mesh;
    for (const AssemblyInstance& in : found.instances) uses += in.mesh == mirroredMesh;
    EXPECT_EQ(uses, 7u) << "the six brackets and the mirrored one";
    // Still where the file put it: the mirrored bracket's world bounds are the flat file's.
    const auto boundsOf = [](const Assembly& a) {
        for (const AssemblyInstance& in : a.instances)
            if (a.parts[in.part].name == "bracket mirrored") return centre(a, in);
        return std::array<double, 3>{};
    };
    const auto fm = boundsOf(found), ff = boundsOf(flat);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(fm[size_t(k)], ff[size_t(k)], 1e-3);
    // Where the declared assembly (gen step without --flat) puts its 21 parts, the flat file's
    // parts are too, after detection (the mirrored bracket aside).
    auto centres = [](const Assembly& a) {
        std::vector<std::array<long, 3>> c;
        for (const AssemblyInstance& in : a.instances) {
            if (a.parts[in.part].name == "bracket mirrored") continue;
            const auto p = centre(a, in);
            c.push_back({std::lround(p[0] * 100), std::lround(p[1] * 100), std::lround(p[2] * 100)});
        }
        std::sort(c.begin(), c.end());
        return c;
    };
    EXPECT_EQ(centres(found), centres(loadAssembly(stepFile())));
    EXPECT_EQ(centres(found), centres(flat));
}

// The import runs in a child process (mesh/src/cad_child.cpp) and hands the assembly back as
// cache bytes in a memfd: the parent's meshes are views of those pages (the geometry exists once),
// and the result is the same as an import in this process, warnings included.
TEST(Step, ChildProcessImportMatchesInProcess) {
    const Assembly child = loadAssembly(stepFile());
    ASSERT_EQ(::setenv("RTWALL_CAD_IN_PROCESS", "1", 1), 0);
    const Assembly here = loadAssembly(stepFile());
    ::unsetenv("RTWALL_CAD_IN_PROCESS");
    ASSERT_EQ(child.meshes.size(), here.meshes.size());
    EXPECT_EQ(child.meshNames, here.meshNames);
    for (size_t m = 0; m < here.meshes.size(); ++m) {
        EXPECT_TRUE(child.meshes[m]->isMapped()) << "the child's pages, not a copy";
        EXPECT_FALSE(here.meshes[m]->isMapped());
        ASSERT_EQ(child.meshes[m]->vertexCount(), here.meshes[m]->vertexCount());
        ASSERT_EQ(child.meshes[m]->triangleCount(), here.meshes[m]->triangleCount());
        EXPECT_EQ(0, std::memcmp(child.meshes[m]->positions(), here.meshes[m]->positions(), 12 * here.meshes[m]->vertexCount()));
        EXPECT_EQ(0, std::memcmp(child.meshes[m]->normals(), here.meshes[m]->normals(), 12 * here.meshes[m]->vertexCount()));
        EXPECT_EQ(0, std::memcmp(child.meshes[m]->indices(), here.meshes[m]->indices(), 12 * here.meshes[m]->triangleCount()));
    }
    ASSERT_NO_FATAL_FAILURE(expectSameInstances(child, here));
    ASSERT_EQ(child.parts.size(), here.parts.size());
    for (size_t i = 0; i < here.parts.size(); ++i) EXPECT_EQ(child.parts[i].name, here.parts[i].name);
    EXPECT_EQ(child.warnings, here.warnings);
}

// Damaged and hostile STEP and IGES files, each made from a real OCCT-written file: every one is
// one line naming the file, from the child process, never a crash or a hang of this process.
TEST(Step, DamagedFilesAreOneLineErrors) {
    const auto dir = test::scratchDir();
    std::ifstream in(stepFile(), std::ios::binary);
    const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(good.size(), 1000u);
    auto replaced = [&](const std::string& from, const std::string& to) {
        std::string s = good;
        const size_t at = s.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        if (at != std::string::npos) s.replace(at, from.size(), to);
        return s;
    };
    // The first entity of the DATA section, whatever it is.
    const size_t data = good.find("DATA;");
    ASSERT_NE(data, std::string::npos);
    const size_t firstEntity = good.find("#", data), firstEnd = good.find(";", firstEntity);
    const std::string entity = good.substr(firstEntity, firstEnd - firstEntity + 1);
    // The placements' points: a coordinate out of double range.
    const size_t point = good.find("CARTESIAN_POINT('',(");
    ASSERT_NE(point, std::string::npos);
    std::string hugeCoordinate = good;
    hugeCoordinate.replace(point + 20, good.find(',', point + 20) - (point + 20), "1.E+400");
    const std::vector<std::pair<std::string, std::string>> files = {
        {"truncated.step", good.substr(0, good.size() / 2)},
        {"truncated_header.step", good.substr(0, 40)},
        {"wrong_header.step", replaced("ISO-10303-21;", "ISO-10303-99;")},
        {"no_data_end.step", replaced("END-ISO-10303-21;", "")},
        {"garbage_entity.step", replaced(entity, entity.substr(0, entity.find('=') + 1) + "((((,,'')#$%&GARBAGE;")},
        {"dangling_reference.step", replaced(entity, entity.substr(0, entity.find('=') + 1) + "AXIS2_PLACEMENT_3D('',#99999999,#99999998,#99999997);")},
        {"huge_entity_number.step", replaced(entity, "#184467440737095516160000" + entity.substr(entity.find('=')))},
        {"huge_coordinate.step", hugeCoordinate},
        {"binary.step", std::string("ISO-10303-21;\n") + std::string(4096, '\xff')},
        {"empty.step", ""},
        {"empty.igs", ""},
        {"garbage.igs", std::string(80 * 20, 'S')},
    };
    for (const auto& [name, text] : files) {
        const fs::path f = test::writeFile(dir / name, text);
        std::string e;
        try {
            const Assembly a = loadAssembly(f);
            // OCCT may recover from some damage (a skipped entity); what it gives must then be
            // an assembly the engine can use.
            EXPECT_FALSE(a.instances.empty()) << name;
            continue;
        } catch (const InputError& err) {
            e = err.what();
        }
        EXPECT_EQ(e.rfind(f.string() + ": ", 0), 0u) << name << ": " << e;
        EXPECT_EQ(e.find('\n'), std::string::npos) << name << ": " << e;
    }
}

// OCCT 7.6 dereferences a null handle when a LINE's VECTOR entity is missing (the fuzzer's first
// crash, within seconds: StepGeom_Vector::Orientation under StepToGeom::MakeLine). In this process
// that is a segmentation fault; the child process makes it one line naming the file.
TEST(Step, CrashInsideOpenCascadeIsContained) {
    const auto dir = test::scratchDir();
    gen::genStepCurved({.out = dir, .instances = 11});
    std::ifstream in(dir / "assembly.step", std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // The first LINE('',#point,#vector): drop the entity #vector.
    const size_t line = text.find("= LINE('',#");
    ASSERT_NE(line, std::string::npos);
    const size_t comma = text.find(",#", line + 11), close = text.find(')', comma);
    const std::string vector = "\n" + text.substr(comma + 1, close - comma - 1) + " = VECTOR(";
    const size_t at = text.find(vector);
    ASSERT_NE(at, std::string::npos) << vector;
    text.erase(at, text.find(';', at) + 1 - at);
    const fs::path bad = test::writeFile(dir / "missing_vector.step", text);
    const std::string e = test::inputErrorOf([&] { loadAssembly(bad); });
    EXPECT_EQ(e.rfind(bad.string() + ": ", 0), 0u) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    EXPECT_NE(e.find("crashed"), std::string::npos) << e;
    // The importer is still usable afterwards.
    EXPECT_EQ(loadAssembly(stepFile()).instances.size(), 21u);
}

TEST(Step, MalformedFilesAreOneLineErrors) {
    const auto dir = test::scratchDir();
    const auto garbage = test::writeFile(dir / "garbage.step", "this is not ISO 10303-21 at all\n");
    const auto empty = test::writeFile(dir / "empty.stp", "");
    const auto noShapes = test::writeFile(dir / "no_shapes.step",
                                          "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('x'),'2;1');\nFILE_NAME('x','',(''),(''),'','','');\n"
                                          "FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n");
    for (const fs::path& f : {garbage, empty, noShapes, dir / "missing.step"}) {
        const std::string e = test::inputErrorOf([&] { loadAssembly(f); });
        EXPECT_EQ(e.rfind(f.string() + ": ", 0), 0u) << e;
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    }
}

}  // namespace
}  // namespace rtwall
