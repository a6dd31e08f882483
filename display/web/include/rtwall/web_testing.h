// A ConsoleBackend without a session, for WebApi's unit tests and its fuzz target: a fixed
// snapshot of a given scene; changes are counted and never run (run() says they did not), so
// every request is checked exactly as against a wall, and nothing can change.
#pragma once

#include <rtwall/web.h>

#include <atomic>

namespace rtwall::testing {

class FakeConsole final : public ConsoleBackend {
public:
    explicit FakeConsole(SceneDesc scene, int wallWidth = 1600, int wallHeight = 1200)
        : scene_(std::move(scene)), parts_(consoleParts(scene_)) {
        auto s = std::make_shared<ConsoleSnapshot>();
        s->frame = 7;
        s->steps = 7;
        s->wallWidth = wallWidth;
        s->wallHeight = wallHeight;
        s->origin = scene_.origin;
        if (!scene_.cameras.empty()) s->session.camera = scene_.cameras.front();
        s->session.sections = scene_.sections;
        auto visibility = std::make_shared<std::vector<Visibility>>();
        for (const InstanceDesc& in : scene_.instances) visibility->push_back(in.visibility);
        s->visibility = std::move(visibility);
        s->session.bookmarks.push_back({"start", s->session.camera});
        s->session.measurements.push_back({{0, 0, 0}, std::array<double, 3>{1, 0, 0}, 1.0});
        snapshot_ = s;
    }
    std::shared_ptr<const ConsoleSnapshot> snapshot() override { return snapshot_; }
    const std::vector<ConsolePart>& parts() override { return parts_; }
    const SceneDesc* scene() override { return &scene_; }
    bool run(std::function<void(WallSession&)>, std::chrono::milliseconds) override {
        ++commands;
        return false;
    }
    std::shared_ptr<const std::vector<uint8_t>> thumbnail(uint32_t*) override { return nullptr; }
    std::optional<Image> screenshot(int, std::chrono::milliseconds, std::string*) override { return std::nullopt; }
    std::shared_ptr<const ConsoleSnapshot> waitNewer(uint64_t, std::chrono::milliseconds) override { return snapshot_; }

    std::atomic<int> commands{0};  // changes asked for (each would have been posted)

private:
    SceneDesc scene_;
    std::vector<ConsolePart> parts_;
    std::shared_ptr<const ConsoleSnapshot> snapshot_;
};

}  // namespace rtwall::testing
