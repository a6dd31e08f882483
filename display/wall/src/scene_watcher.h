// `rtwall run --watch`: the scene file is reloaded on a background thread whenever it changes on
// disk, so that the wall keeps running while a large scene loads again.
#pragma once

#include <rtwall/engine.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <future>
#include <optional>
#include <string>

namespace rtwall::wall {

class SceneWatcher {
public:
    // `load` reads the file (on the background thread); `report` gets one line per file that
    // does not load.
    SceneWatcher(std::filesystem::path file, std::function<SceneDesc()> load, std::function<void(const std::string&)> report)
        : file_(std::move(file)), load_(std::move(load)), report_(std::move(report)), lastWrite_(writeTime()) {}

    // The reloaded scene once the file changed and its load finished. A file that does not load
    // (an edit half-written, a typo) is reported in one line and the running scene stays.
    std::optional<SceneDesc> poll() {
        const auto now = std::chrono::steady_clock::now();
        if (!loading_.valid() && now - lastCheck_ > std::chrono::milliseconds(200)) {
            lastCheck_ = now;
            const auto t = writeTime();
            if (t && t != lastWrite_) {
                lastWrite_ = t;
                loading_ = std::async(std::launch::async, load_);
            }
        }
        if (!loading_.valid() || loading_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return std::nullopt;
        try {
            return loading_.get();
        } catch (const std::exception& e) {
            report_(std::string("--watch: ") + e.what() + " (the running scene stays)");
            return std::nullopt;
        }
    }

private:
    std::optional<std::filesystem::file_time_type> writeTime() const {
        std::error_code ec;
        const auto t = std::filesystem::last_write_time(file_, ec);
        return ec ? std::nullopt : std::optional(t);
    }
    std::filesystem::path file_;
    std::function<SceneDesc()> load_;
    std::function<void(const std::string&)> report_;
    std::optional<std::filesystem::file_time_type> lastWrite_;
    std::chrono::steady_clock::time_point lastCheck_{};
    std::future<SceneDesc> loading_;
};

}  // namespace rtwall::wall
