// Hide, isolate and highlight on the wall (issue 20): Ctrl+click picks a part, X hides it, I
// isolates it, G highlights it, U shows all; --hide etc. (RunConfig::parts) apply from the start.
// Every frame the cluster shows is the session's state rendered on one machine, byte for byte.
#include "display_test_util.h"
#include "parts_scene.h"
#include "session_test_util.h"

#include <rtwall/wall.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <gtest/gtest.h>

#include <memory>

namespace rtwall {
namespace {

RunConfig partsConfig(const std::filesystem::path& dir, std::shared_ptr<std::vector<std::string>> lines) {
    RunConfig c = steppedRunConfig(dir);
    c.scene = "parts";
    c.loaded = test::partsScene();
    c.cluster.async = false;
    c.log = [lines](const std::string& line) { lines->push_back(line); };
    return c;
}

// A wall pixel whose ray hits `instance` first.
std::pair<double, double> pixelOnInstance(WallSession& s, uint32_t instance) {
    const RenderSettings& st = s.scene().settings;
    for (int y = 0; y < st.height; ++y)
        for (int x = 0; x < st.width; ++x)
            if (const auto hit = s.pick(x + 0.5, y + 0.5); hit && hit->instance == instance) return {x + 0.5, y + 0.5};
    ADD_FAILURE() << "instance " << instance << " is not in view";
    return {0, 0};
}

void ctrlClick(WallSession& s, std::pair<double, double> at) {
    s.inject(test::ctrlClick(at));
    s.inject(InputState{});  // released
}

void key(WallSession& s, int k) { s.inject(test::keyPress(k)); }

TEST(PartsSession, PickThenHideIsolateHighlightAndShowAll) {
    const auto dir = test::scratchDir();
    auto lines = std::make_shared<std::vector<std::string>>();
    WallSession s(partsConfig(dir, lines));
    ASSERT_TRUE(s.step());
    const Image start = s.lastFrame().left;
    ASSERT_EQ(test::differingBytes(start, test::renderFirstCamera(s.scene())), 0u);

    key(s, GLFW_KEY_X);  // nothing picked yet: nothing happens
    ASSERT_TRUE(s.step());
    EXPECT_TRUE(test::logged(*lines, "parts: Ctrl+click a part first"));

    ctrlClick(s, pixelOnInstance(s, 1));
    ASSERT_TRUE(s.step());
    EXPECT_TRUE(test::logged(*lines, "part 'asm/left'"));
    key(s, GLFW_KEY_X);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().instances[1].visibility, Visibility::Hidden);
    EXPECT_EQ(s.partView().hide, std::vector<std::string>{"asm/left"});
    EXPECT_EQ(test::bytesOffState(s), 0u);
    EXPECT_GT(test::differingBytes(s.lastFrame().left, start), 0u);
    EXPECT_TRUE(test::logged(*lines, "parts: hidden 'asm/left'; 1 of 4 instances hidden"));

    ctrlClick(s, pixelOnInstance(s, 2));
    key(s, GLFW_KEY_I);  // the right box's node: the box and its knob, nothing else
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().instances[0].visibility, Visibility::Hidden);
    EXPECT_EQ(s.scene().instances[2].visibility, Visibility::Shown);
    EXPECT_EQ(s.scene().instances[3].visibility, Visibility::Shown);
    EXPECT_EQ(test::bytesOffState(s), 0u);
    EXPECT_TRUE(test::logged(*lines, "isolated 'asm/right'"));

    key(s, GLFW_KEY_G);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().instances[2].visibility, Visibility::Highlighted);
    EXPECT_EQ(s.scene().instances[3].visibility, Visibility::Highlighted);
    EXPECT_EQ(test::bytesOffState(s), 0u);

    key(s, GLFW_KEY_U);
    ASSERT_TRUE(s.step());
    for (const InstanceDesc& in : s.scene().instances) EXPECT_EQ(in.visibility, Visibility::Shown);
    EXPECT_EQ(test::bytesOffState(s), 0u);
}

TEST(PartsSession, RunConfigPartsApplyFromTheStart) {
    const auto dir = test::scratchDir();
    auto lines = std::make_shared<std::vector<std::string>>();
    RunConfig c = partsConfig(dir, lines);
    c.parts.hide = {"knob"};
    c.parts.highlight = {"left"};
    WallSession s(c);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().instances[3].visibility, Visibility::Hidden);
    EXPECT_EQ(s.scene().instances[1].visibility, Visibility::Highlighted);
    EXPECT_EQ(test::bytesOffState(s), 0u);
    EXPECT_TRUE(test::logged(*lines, "1 of 4 instances hidden, 1 highlighted"));
    // A wall view on top keeps them; U shows all.
    s.setPartView(PartView{{"floor"}, {}, {}});
    EXPECT_EQ(s.scene().instances[3].visibility, Visibility::Hidden);
    EXPECT_EQ(s.scene().instances[0].visibility, Visibility::Hidden);
    EXPECT_THROW(s.setPartView(PartView{{"nothing"}, {}, {}}), InputError);
    EXPECT_EQ(s.scene().instances[0].visibility, Visibility::Hidden) << "a bad pattern changes nothing";
    s.showAllParts();
    ASSERT_TRUE(s.step());
    for (const InstanceDesc& in : s.scene().instances) EXPECT_EQ(in.visibility, Visibility::Shown);
    EXPECT_EQ(test::bytesOffState(s), 0u);
}

// A --watch edit of the scene file's [parts] arrives as visibility changes (applyEdit is what the
// watcher calls); the wall's own view stays on top of it.
TEST(PartsSession, AnEditedPartsTableIsAnUpdate) {
    const auto dir = test::scratchDir();
    auto lines = std::make_shared<std::vector<std::string>>();
    WallSession s(partsConfig(dir, lines));
    ASSERT_TRUE(s.step());
    s.setPartView(PartView{{}, {}, {"left"}});
    SceneDesc edited = test::partsScene();
    applyPartView(edited, PartView{{"floor"}, {}, {}});
    const SceneEdit e = s.applyEdit(edited);
    EXPECT_TRUE(e.refused.empty());
    EXPECT_TRUE(e.transforms.empty());
    ASSERT_EQ(e.visibility.size(), 2u) << "the floor, and the left box the wall highlights";
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().instances[0].visibility, Visibility::Hidden);
    EXPECT_EQ(s.scene().instances[1].visibility, Visibility::Highlighted);
    EXPECT_EQ(test::bytesOffState(s), 0u);
    EXPECT_TRUE(test::logged(*lines, "camera same, 0 section planes, 2 instance visibilities"));
}

}  // namespace
}  // namespace rtwall
