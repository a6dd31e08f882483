// Hide, isolate and highlight parts by name (issue 20): the patterns, and what the renderer
// makes of them. A hidden part leaves no pixel, no shadow and no reflection: its frame is
// bit-identical to the frame of a scene that never had it. A highlight changes that part's
// pixels only.
#include "parts_scene.h"
#include "test_util.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <algorithm>

namespace rtwall {
namespace {

using test::partsScene;

Image render(const SceneDesc& d) { return test::renderFirstCamera(d, 1); }

size_t differingPixels(const Image& a, const Image& b) {
    size_t n = 0;
    for (size_t i = 0; i + 2 < a.rgb.size(); i += 3)
        n += a.rgb[i] != b.rgb[i] || a.rgb[i + 1] != b.rgb[i + 1] || a.rgb[i + 2] != b.rgb[i + 2];
    return n;
}

// The scene with only the instances `keep` says.
SceneDesc without(SceneDesc d, std::vector<uint32_t> drop) {
    std::sort(drop.rbegin(), drop.rend());
    for (uint32_t i : drop) d.instances.erase(d.instances.begin() + i);
    return d;
}

TEST(Parts, GlobMatches) {
    EXPECT_TRUE(globMatch("bolt*", "bolt 12"));
    EXPECT_TRUE(globMatch("*", ""));
    EXPECT_TRUE(globMatch("a*b*c", "aXXbYYc"));
    EXPECT_TRUE(globMatch("engine/*/piston 2", "engine/block/piston 2"));
    EXPECT_FALSE(globMatch("bolt", "bolt 1"));
    EXPECT_FALSE(globMatch("a*b", "ac"));
    EXPECT_FALSE(globMatch("*x", "abc"));
}

TEST(Parts, PatternsMatchNamesPathsAndEverythingBelow) {
    const SceneDesc d = partsScene();
    EXPECT_EQ(instancesMatching(d, "left"), (std::vector<uint32_t>{1}));
    // A node's instances and those of every node below it.
    EXPECT_EQ(instancesMatching(d, "asm/right"), (std::vector<uint32_t>{2, 3}));
    EXPECT_EQ(instancesMatching(d, "right"), (std::vector<uint32_t>{2, 3}));
    EXPECT_EQ(instancesMatching(d, "asm"), (std::vector<uint32_t>{1, 2, 3}));
    EXPECT_EQ(instancesMatching(d, "asm/right/knob"), (std::vector<uint32_t>{3}));
    EXPECT_EQ(instancesMatching(d, "*/knob"), (std::vector<uint32_t>{3}));
    // An instance without a part goes by its mesh's name; a path never names it.
    EXPECT_EQ(instancesMatching(d, "floor"), (std::vector<uint32_t>{0}));
    EXPECT_TRUE(instancesMatching(d, "*/floor").empty());
    EXPECT_TRUE(instancesMatching(d, "asm/left/x").empty());
    const std::string e = test::inputErrorOf([&] { visibilityOf(d, PartView{{"nothing*"}, {}, {}}); });
    EXPECT_NE(e.find("hide 'nothing*': no part or mesh matches it"), std::string::npos) << e;
}

TEST(Parts, IsolateHideAndHighlightCombine) {
    const SceneDesc d = partsScene();
    using V = Visibility;
    EXPECT_EQ(visibilityOf(d, PartView{{}, {"right"}, {}}), (std::vector<V>{V::Hidden, V::Hidden, V::Shown, V::Shown}));
    EXPECT_EQ(visibilityOf(d, PartView{{"knob"}, {"right"}, {"asm"}}),
              (std::vector<V>{V::Hidden, V::Hidden, V::Highlighted, V::Hidden}));
    SceneDesc e = d;
    applyPartView(e, PartView{{"left"}, {}, {}});
    applyPartView(e, PartView{{}, {}, {"asm"}});  // on top: the hidden part stays hidden
    EXPECT_EQ(e.instances[1].visibility, V::Hidden);
    EXPECT_EQ(e.instances[2].visibility, V::Highlighted);
}

// The hidden box's pixels, and its shadow on the floor, are gone: the frame is the frame of the
// scene without it, byte for byte.
TEST(Parts, HiddenPartLeavesNoPixelAndNoShadow) {
    const SceneDesc d = partsScene();
    const Image all = render(d);
    SceneDesc hidden = d;
    applyPartView(hidden, PartView{{"left"}, {}, {}});
    const Image withoutLeft = render(without(d, {1}));
    ASSERT_GT(differingPixels(all, withoutLeft), 100u) << "the left box and its shadow must show in the full frame";
    EXPECT_EQ(differingPixels(render(hidden), withoutLeft), 0u);

    // Also as a differential update of a built scene, and back.
    Scene scene(d);
    const Camera cam(d.cameras.front(), d.settings.width, d.settings.height);
    scene.setInstanceVisibility(1, Visibility::Hidden);
    scene.commit();
    EXPECT_EQ(differingPixels(renderFrame(scene, cam, d.settings, 1), withoutLeft), 0u);
    EXPECT_FALSE(pick(scene, cam, 0, 0).has_value() && pick(scene, cam, 0, 0)->instance == 1);
    scene.setInstanceVisibility(1, Visibility::Shown);
    scene.commit();
    EXPECT_EQ(differingPixels(renderFrame(scene, cam, d.settings, 1), all), 0u);
    EXPECT_THROW(scene.setInstanceVisibility(4, Visibility::Hidden), std::out_of_range);
}

TEST(Parts, IsolateShowsOnlyThosePartsAndWhatIsBelowThem) {
    const SceneDesc d = partsScene();
    SceneDesc isolated = d;
    applyPartView(isolated, PartView{{}, {"asm/right"}, {}});
    EXPECT_EQ(differingPixels(render(isolated), render(without(d, {0, 1}))), 0u);
}

// A highlight changes the pixels where that part is seen (and nowhere else: the floor and the
// other parts keep their bytes), and it shows both lit and in shadow.
TEST(Parts, HighlightChangesOnlyThatPartsPixels) {
    const SceneDesc d = partsScene();
    SceneDesc lit = d;
    applyPartView(lit, PartView{{}, {}, {"left"}});
    const Image plain = render(d), highlighted = render(lit);
    const Scene scene(d);
    const Camera cam(d.cameras.front(), d.settings.width, d.settings.height);
    size_t onPart = 0, changedOnPart = 0, changedElsewhere = 0;
    for (int y = 0; y < d.settings.height; ++y)
        for (int x = 0; x < d.settings.width; ++x) {
            const std::optional<PickResult> hit = pick(scene, cam, float(x) + 0.5f, float(y) + 0.5f);
            const size_t i = (size_t(y) * size_t(d.settings.width) + size_t(x)) * 3;
            const bool changed = plain.rgb[i] != highlighted.rgb[i] || plain.rgb[i + 1] != highlighted.rgb[i + 1] ||
                                 plain.rgb[i + 2] != highlighted.rgb[i + 2];
            if (hit && hit->instance == 1) {
                ++onPart;
                changedOnPart += changed;
                // Warmer: the red channel gains on the blue one.
                if (changed) {
                    EXPECT_GT(int(highlighted.rgb[i]) - int(highlighted.rgb[i + 2]), int(plain.rgb[i]) - int(plain.rgb[i + 2]));
                }
            } else {
                changedElsewhere += changed;
            }
        }
    ASSERT_GT(onPart, 50u);
    EXPECT_EQ(changedOnPart, onPart);
    EXPECT_EQ(changedElsewhere, 0u);
    // The eye-light preview shows it too.
    SceneDesc eye = d, eyeLit = lit;
    eye.settings.shading = eyeLit.settings.shading = ShadingMode::EyeLight;
    EXPECT_GT(differingPixels(render(eye), render(eyeLit)), onPart / 2);
}

}  // namespace
}  // namespace rtwall
