// Part moves at frame rate (issue 29): a moved instance leaves the static top level for a small
// level of its own, the static one is rebuilt in the background, and every image on the way is
// the image of a scene built afresh in the same state, whichever level holds which instance.
#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace rtwall {
namespace {

constexpr int kW = 96, kH = 64, kSide = 20;

// A 20 x 20 grid of boxes on a floor under a point light; box 21 is glass and box 42 has an
// alpha mask, so shadow rays walk through glass and filters run in both levels.
SceneDesc grid() {
    SceneDesc d;
    d.meshes.push_back({"box", "shape:box", std::make_shared<const TriangleMesh>(makeBox())});
    d.meshes.push_back({"quad", "shape:quad", std::make_shared<const TriangleMesh>(makeQuad())});
    Material grey;
    grey.name = "grey";
    Material glass;
    glass.name = "glass";
    glass.type = MaterialType::Glass;
    glass.color = {0.9f, 1.0f, 0.9f};
    Material leaf;
    leaf.name = "leaf";
    leaf.color = {0.2f, 0.7f, 0.2f};
    leaf.alpha.kind = TextureKind::Checker;
    leaf.alpha.scale = 0.3f;
    leaf.alpha.color2 = {0, 0, 0};
    d.materials = {grey, glass, leaf};
    d.instances.push_back({1, 0, Transform::scale(20, 1, 20)});  // the floor, instance 0
    for (int i = 0; i < kSide * kSide; ++i) {
        const double x = 1.5 * (i % kSide - kSide / 2), z = 1.5 * (i / kSide - kSide / 2);
        const uint32_t material = i == 20 ? 1 : i == 41 ? 2 : 0;
        d.instances.push_back({0, material, Transform::translate(x, 0.5, z) * Transform::scale(0.5, 0.5, 0.5)});
    }
    Light l;
    l.position = {3, 12, 6};
    l.intensity = 150;
    d.lights.push_back(l);
    CameraDesc c;
    c.position = {0, 14, 16};
    c.lookAt = {0, 0, 0};
    d.cameras.push_back(c);
    d.settings.width = kW;
    d.settings.height = kH;
    d.settings.threads = 2;
    d.settings.maxDepth = 4;
    d.settings.ambient = {0.1f, 0.1f, 0.1f};
    return d;
}

Image render(const Scene& scene, KernelType kernel = KernelType::Packet) {
    RenderSettings s = scene.desc().settings;
    s.kernel = kernel;
    return renderFrame(scene, Camera(scene.desc().cameras.front(), kW, kH), s);
}

// `live`'s image against a scene built afresh from its state, for each kernel. (Each kernel
// against its own fresh image: on this scene the two kernels differ in 3 pixels of the far
// glass box, with or without moves; see the issue 29 note.)
void expectAsFresh(const Scene& live, const std::string& when) {
    const Scene fresh(live.desc());
    for (KernelType kernel : {KernelType::Packet, KernelType::Single})
        EXPECT_TRUE(render(live, kernel).rgb == render(fresh, kernel).rgb)
            << when << (kernel == KernelType::Single ? " (single rays)" : " (packets)");
}

size_t differingPixels(const Image& a, const Image& b) {
    size_t n = 0;
    for (size_t i = 0; i + 2 < a.rgb.size() && a.rgb.size() == b.rgb.size(); i += 3)
        n += a.rgb[i] != b.rgb[i] || a.rgb[i + 1] != b.rgb[i + 1] || a.rgb[i + 2] != b.rgb[i + 2];
    return a.rgb.size() == b.rgb.size() ? n : SIZE_MAX;
}

Transform lifted(const SceneDesc& d, uint32_t i, int step) {
    return Transform::translate(0.3 * step, 0.4 * (step % 3), -0.2 * step) * d.instances[i].transform;
}

// Every mover rests (10 commits), then instance i starts moving; after the rebuild that follows.
Scene::TopLevelState restThenMove(Scene& live, const SceneDesc& d, uint32_t i) {
    for (int k = 0; k < 10; ++k) live.commit();
    live.setInstanceTransform(i, lifted(d, i, 1));
    live.commit();
    live.waitForRebuild();
    return live.topLevelState();
}

class Moves : public ::testing::TestWithParam<int> {};

// 1 and 100 parts dragged over several frames: each frame as a fresh scene; the static level is
// rebuilt in the background without them, and published by a commit.
TEST_P(Moves, EveryFrameIsTheImageOfAFreshScene) {
    const int movers = GetParam();
    const SceneDesc d = grid();
    Scene live(d);
    const Image before = render(live);
    for (int step = 1; step <= 4; ++step) {
        for (int k = 0; k < movers; ++k) {
            const auto i = uint32_t(1 + (k * 37) % (kSide * kSide));  // glass (21) and leaf (42) among the 100
            live.setInstanceTransform(i, lifted(d, i, step));
        }
        live.commit();
        const Scene::TopLevelState st = live.topLevelState();
        EXPECT_EQ(st.moving, size_t(movers)) << step;
        expectAsFresh(live, "step " + std::to_string(step));
    }
    EXPECT_FALSE(render(live).rgb == before.rgb) << "the moves show";
    live.waitForRebuild();
    Scene::TopLevelState st = live.topLevelState();
    EXPECT_EQ(st.stale, 0u);  // the new static level was built without the movers
    EXPECT_EQ(st.moving, size_t(movers));
    EXPECT_FALSE(st.rebuilding);
    expectAsFresh(live, "after the rebuild");
}
INSTANTIATE_TEST_SUITE_P(OneAndAHundred, Moves, ::testing::Values(1, 100));

// Instances the scene marks movable (InstanceDesc::movable) live in the moving level from the
// start: dragging them never makes the static level stale nor starts a rebuild, resting never
// folds them back, and every image is the image of the same state built without the marks.
TEST(Moves, MovableInstancesNeverRebuildTheStaticLevel) {
    SceneDesc d = grid();
    const std::vector<uint32_t> marked = {5, 21, 42};  // a grey box, the glass one and the leaf
    for (uint32_t i : marked) d.instances[i].movable = true;
    const auto unmarked = [](SceneDesc x) {
        for (InstanceDesc& in : x.instances) in.movable = false;
        return x;
    };
    Scene live(d), dragged(unmarked(d));  // `dragged`: the same moves of unmarked parts
    Scene::TopLevelState st = live.topLevelState();
    EXPECT_EQ(st.moving, 3u);
    EXPECT_EQ(st.stale, 0u);
    EXPECT_TRUE(render(live).rgb == render(Scene(unmarked(live.desc()))).rgb);
    for (int step = 1; step <= 12; ++step) {
        for (uint32_t i : marked) {
            live.setInstanceTransform(i, lifted(d, i, step));
            dragged.setInstanceTransform(i, lifted(d, i, step));
        }
        live.commit();
        dragged.commit();
        st = live.topLevelState();
        EXPECT_EQ(st.moving, 3u) << step;
        EXPECT_EQ(st.stale, 0u) << step;
        EXPECT_FALSE(st.rebuilding) << step << ": a marked part's move rebuilt the static level";
        if (step % 4 != 0) continue;
        dragged.waitForRebuild();
        const Scene plain(unmarked(live.desc()));
        for (KernelType kernel : {KernelType::Packet, KernelType::Single}) {
            const std::string what = "step " + std::to_string(step) + (kernel == KernelType::Single ? " (single rays)" : " (packets)");
            const Image image = render(live, kernel);
            EXPECT_EQ(differingPixels(image, render(dragged, kernel)), 0u) << what << ": as the unmarked parts dragged there";
            // Against the state built afresh: equal. At step 12 the glass box rests on the floor,
            // and two single rays hit its bottom and the floor at the same distance: the tie rule
            // (scene_impl.h, TopContext) picks the same one whichever level holds the box.
            EXPECT_EQ(differingPixels(image, render(plain, kernel)), 0u) << what;
        }
    }
    // An unmarked part still goes the usual way, and its rebuild leaves the marked ones out.
    live.setInstanceTransform(7, lifted(d, 7, 1));
    live.commit();
    live.waitForRebuild();
    st = restThenMove(live, d, 9);  // 7 and the marked ones rest
    EXPECT_EQ(st.moving, 4u) << "7 rested and was folded back; the marked three stay; 9 moves";
    EXPECT_EQ(st.stale, 0u);
    expectAsFresh(live, "marked and unmarked movers");
}

// Movers that rest are folded back into the static level by the next rebuild; one moved while a
// rebuild that holds it runs is stale in what it publishes; a visibility change during a
// rebuild drops it (the next commit starts another).
TEST(Moves, SettledMoversFoldBackAndRacesStayExact) {
    const SceneDesc d = grid();
    Scene live(d);
    live.setInstanceTransform(5, lifted(d, 5, 1));
    live.commit();
    live.waitForRebuild();
    EXPECT_EQ(live.topLevelState().moving, 1u);
    for (int i = 0; i < 10; ++i) live.commit();  // instance 5 rests
    live.setInstanceTransform(7, lifted(d, 7, 2));  // another part starts moving: a rebuild folds 5 in
    live.commit();
    live.setInstanceTransform(5, lifted(d, 5, 3));  // ... and 5 moves again while it runs
    live.waitForRebuild();
    Scene::TopLevelState st = live.topLevelState();
    EXPECT_EQ(st.moving, 2u);
    EXPECT_EQ(st.stale, 1u) << "5's copy in the new static level is from before its last move";
    live.commit();
    expectAsFresh(live, "5 stale in the new static level");
    st = restThenMove(live, d, 9);
    EXPECT_EQ(st.moving, 1u) << "5 and 7 rested and were folded back; 9 moves";
    EXPECT_EQ(st.stale, 0u);
    expectAsFresh(live, "after folding");

    // A part hidden while a rebuild runs: that rebuild is dropped, the next one published.
    live.setInstanceTransform(11, lifted(d, 11, 1));
    live.commit();
    live.setInstanceVisibility(30, Visibility::Hidden);
    live.commit();
    live.waitForRebuild();
    live.commit();
    live.waitForRebuild();
    EXPECT_EQ(live.topLevelState().stale, 0u);
    expectAsFresh(live, "a part hidden during a rebuild");

    // Picking sees the moved part where it is, not where it was: as on a fresh scene.
    const Camera cam(d.cameras.front(), kW, kH);
    const Scene fresh(live.desc());
    int moved = 0;
    for (int y = 0; y < kH; y += 2)
        for (int x = 0; x < kW; x += 2) {
            const auto a = pick(live, cam, float(x) + 0.5f, float(y) + 0.5f);
            const auto b = pick(fresh, cam, float(x) + 0.5f, float(y) + 0.5f);
            ASSERT_EQ(a.has_value(), b.has_value()) << x << "," << y;
            if (!a) continue;
            EXPECT_EQ(a->instance, b->instance) << x << "," << y;
            moved += a->instance == 11;
        }
    EXPECT_GT(moved, 0) << "the moved part is picked somewhere";
}

}  // namespace
}  // namespace rtwall
