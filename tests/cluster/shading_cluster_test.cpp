// Shading over the cluster: every material, GI with progressive frames, material updates and
// the client false-colour view give exactly the single-machine bytes (or, for the client view,
// the ids the master assigned).
#include "shading_scenes.h"
#include "local_cluster.h"
#include "test_util.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>

#include <memory>
#include <set>
#include <thread>

namespace rtwall {
namespace {

using test::LocalCluster;
using test::differingBytes;
using test::singleMachine;

TEST(ClusterShading, EveryMaterialAndGiBitIdenticalToOneMachine) {
    const auto dir = test::scratchDir();
    SceneDesc desc = test::zooInTilesOf8(dir, 64, 48);
    LocalCluster cluster(desc, test::eightBitFrames(), 3);
    Master& master = *cluster.master;
    ASSERT_TRUE(cluster.ready());
    cluster.expectFrameOf(desc, "whitted");

    // GI: each frame has its own seeds; the cluster's progressive mean equals one machine's.
    SceneDesc gi = desc;
    gi.settings.gi = true;
    gi.settings.samples = 2;
    master.setRenderSettings(gi.settings);
    Accumulator clusterAcc, localAcc;
    for (int f = 0; f < 3; ++f) {
        FrameReport r;
        const Image img = cluster.expectFrameOf(gi, "gi", &r);
        clusterAcc.add(img);
        localAcc.add(singleMachine(gi, r.frame));
    }
    EXPECT_EQ(differingBytes(clusterAcc.resolve(), localAcc.resolve()), 0u);

    // A material changed at run time (glass becomes rough metal, the floor gets marble).
    SceneDesc changed = gi;
    changed.materials[4].type = MaterialType::Metal;
    changed.materials[4].roughness = 0.2f;
    changed.materials[0].texture.kind = TextureKind::Marble;
    master.setMaterial(4, changed.materials[4]);
    master.setMaterial(0, changed.materials[0]);
    cluster.expectFrameOf(changed, "after material updates");

    // The leaf's checker mask becomes a hashed alpha (glTF's BLEND, protocol version 19): every
    // client flips the same coins for the same rays.
    changed.materials[7].alphaMode = AlphaMode::Hashed;
    changed.materials[7].opacity = 0.6f;
    master.setMaterial(7, changed.materials[7]);
    cluster.expectFrameOf(changed, "after the leaf's hashed alpha");
}

// An area light with a visible face (an emitting panel in its place, counted once by multiple
// importance sampling) and two-sided emission (protocol version 6): GI frames over three clients
// equal one machine's, also after updates that make the lamp two-sided and move the light off
// its panel (each client finds the faces again, as one machine does).
TEST(ClusterShading, LampFacesAndTwoSidedEmissionBitIdenticalToOneMachine) {
    const auto dir = test::scratchDir();
    SceneDesc desc = test::zooInTilesOf8(dir, 48, 36, 2);
    Material panel = test::material("panel", MaterialType::Emissive, {1, 1, 1});
    panel.emission = {3, 3, 3};  // the zoo's area light: radiance 3 over [0.5, 1.5] x [-1.5, -0.5] at y 3.5
    desc.materials.push_back(panel);
    desc.instances.push_back({1, uint32_t(desc.materials.size() - 1),
                              Transform::translate(1.0, 3.505, -1.0) * Transform::rotateDegrees(1, 0, 0, 180) *
                                  Transform::scale(0.5, 1, 0.5)});
    ASSERT_EQ(Scene(desc).lightFace(1), LightFace::Covered);
    LocalCluster cluster(desc, test::eightBitFrames(), 3);
    Master& master = *cluster.master;
    ASSERT_TRUE(cluster.ready());
    for (int f = 0; f < 2; ++f) cluster.expectFrameOf(desc, "one-sided");
    SceneDesc changed = desc;
    changed.materials.back().twoSided = true;
    changed.lights[1].twoSided = true;
    changed.lights[1].position.y = 3.0f;  // off its panel: the panel is an emitter of its own again
    ASSERT_EQ(Scene(changed).lightFace(1), LightFace::None);
    master.setMaterial(uint32_t(changed.materials.size() - 1), changed.materials.back());
    master.setLight(1, changed.lights[1]);
    cluster.expectFrameOf(changed, "after the updates");
}

// Section planes (issue 20, protocol version 9): a scene that starts with one plane (in the
// snapshot) renders over three clients as on one machine; then a plane moved, one added and one
// turned off as differential updates.
TEST(ClusterShading, SectionPlanesAndTheirUpdatesBitIdenticalToOneMachine) {
    const auto dir = test::scratchDir();
    SceneDesc desc = test::zooInTilesOf8(dir, 64, 48);
    desc.sections[1].enabled = true;
    desc.sections[1].point = {0.3f, 0, 0};
    desc.sections[1].normal = {-1, 0, 0.2f};
    LocalCluster cluster(desc, test::eightBitFrames(), 3);
    Master& master = *cluster.master;
    ASSERT_TRUE(cluster.ready());
    const Image before = cluster.expectFrameOf(desc, "the snapshot's plane");

    SceneDesc changed = desc;
    changed.sections[1].point = {-0.5f, 0, 0};
    changed.sections[4].enabled = true;
    changed.sections[4].point = {0, 0, -0.2f};
    changed.sections[4].normal = {0, 0, -1};
    changed.sections[4].capColor = {0.1f, 0.2f, 0.9f};
    master.setSection(1, changed.sections[1]);
    master.setSection(4, changed.sections[4]);
    EXPECT_GT(differingBytes(cluster.expectFrameOf(changed, "a plane moved and one added"), before), 0u)
        << "the updates changed the picture";

    changed.sections[1].enabled = false;
    master.setSection(1, changed.sections[1]);
    EXPECT_THROW(master.setSection(kMaxSections, changed.sections[1]), std::exception);
    SectionPlane flat = changed.sections[1];
    flat.normal = {0, 0, 0};
    EXPECT_THROW(master.setSection(2, flat), std::invalid_argument);
    cluster.expectFrameOf(changed, "a plane turned off");
}

// Texture coordinates travel with the mesh (protocol version 5): a UV-textured OBJ (an image by
// uv, an alpha mask by uv and a uv bump, with a seam split on import) over two clients gives one
// machine's bytes.
TEST(ClusterShading, UVTexturedMeshBitIdenticalToOneMachine) {
    const auto dir = test::scratchDir();
    SceneDesc desc = test::zooInTilesOf8(dir, 64, 48);
    const std::string file = (test::dataDir() / "meshes" / "uv_seam.obj").string();
    auto mesh = std::make_shared<const TriangleMesh>(loadMesh(file));
    ASSERT_TRUE(mesh->hasUVs());
    desc.meshes.push_back({"uvmesh", file, mesh});
    Material textured = test::material("uvimage", MaterialType::Lambert, {1, 1, 1});
    textured.texture.kind = TextureKind::Image;
    textured.texture.file = test::writeTestTexture(dir);
    textured.texture.mapping = TextureMapping::Uv;
    textured.alpha.kind = TextureKind::Checker;
    textured.alpha.color2 = {0, 0, 0};
    textured.alpha.scale = 0.25f;
    textured.alpha.mapping = TextureMapping::Uv;
    textured.bump = 0.2f;
    textured.bumpScale = 0.1f;
    textured.bumpMapping = TextureMapping::Uv;
    desc.materials.push_back(textured);
    const uint32_t meshIndex = uint32_t(desc.meshes.size() - 1), materialIndex = uint32_t(desc.materials.size() - 1);
    desc.instances.push_back({meshIndex, materialIndex, Transform::translate(-1.0, 0.3, 0.5) * Transform::scale(1.5, 1.5, 1.5)});
    desc.instances.push_back({meshIndex, materialIndex, Transform::translate(0.5, 1.2, 0.0) * Transform::rotateDegrees(1, 0, 0, 80)});
    LocalCluster cluster(desc, test::eightBitFrames(), 2);
    ASSERT_TRUE(cluster.ready());
    FrameReport r;
    cluster.expectFrameOf(desc, "the UV mesh", &r);
    const Image local = singleMachine(desc, r.frame);
    // The UV mesh is in the picture: without it the frame differs.
    SceneDesc without = desc;
    without.instances.resize(without.instances.size() - 2);
    EXPECT_GT(differingBytes(local, singleMachine(without, r.frame)), 100u);
}

TEST(ClusterShading, ClientViewShowsTheIdsTheMasterAssigned) {
    const auto dir = test::scratchDir();
    SceneDesc desc = test::zooInTilesOf8(dir, 64, 48);
    desc.settings.view = ViewMode::Client;
    ClusterSettings cs = test::inStep();
    cs.prefetch = 1;
    LocalCluster cluster(desc, cs, 3);
    ASSERT_TRUE(cluster.ready());
    FrameReport r;
    const Image img = cluster.master->renderFrame(&r);
    std::set<uint32_t> colours;
    for (size_t i = 0; i + 2 < img.rgb.size(); i += 3)
        colours.insert(uint32_t(img.rgb[i]) << 16 | uint32_t(img.rgb[i + 1]) << 8 | img.rgb[i + 2]);
    size_t busy = 0;
    for (const ClientReport& c : r.clients) busy += c.tiles > 0;
    EXPECT_EQ(colours.size(), busy) << "one colour per client that rendered tiles";
    // Each colour is the one its id gives on one machine.
    for (const ClientReport& c : r.clients) {
        if (c.tiles == 0) continue;
        TraceOptions trace;
        trace.clientId = c.id;
        const Image ref = renderFrame(Scene(desc), Camera(desc.cameras.front(), desc.settings.width, desc.settings.height),
                                      desc.settings, r.frame, nullptr, trace);
        const uint32_t colour = uint32_t(ref.rgb[0]) << 16 | uint32_t(ref.rgb[1]) << 8 | ref.rgb[2];
        EXPECT_TRUE(colours.count(colour)) << "client " << c.id;
    }
}

}  // namespace
}  // namespace rtwall
