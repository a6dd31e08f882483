#include <rtwall/tune.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace rtwall {

std::optional<double> OperatingPoint::control(const std::string& key) const {
    for (const auto& [k, v] : controls)
        if (k == key) return v;
    return std::nullopt;
}

std::vector<OperatingPoint> paretoFront(const std::vector<OperatingPoint>& points) {
    std::vector<size_t> order(points.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    // Fastest first; among equally fast, most accurate first; then input order (stable).
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (points[a].frameSeconds != points[b].frameSeconds) return points[a].frameSeconds < points[b].frameSeconds;
        return points[a].error < points[b].error;
    });
    std::vector<OperatingPoint> front;
    for (size_t i : order)
        // Every point kept so far is at least as fast; this one stays only if it is strictly
        // more accurate than all of them.
        if (front.empty() || points[i].error < front.back().error) front.push_back(points[i]);
    return front;
}

OperatingPointController::OperatingPointController(std::vector<OperatingPoint> points, ControllerOptions options)
    : options_(options) {
    if (points.empty()) throw InputError("operating point: the front is empty");
    for (const OperatingPoint& p : points) {
        if (!(p.frameSeconds > 0) || !std::isfinite(p.frameSeconds))
            throw InputError("operating point '" + p.name + "': frame time must be positive");
        if (!(p.error >= 0) || !std::isfinite(p.error))
            throw InputError("operating point '" + p.name + "': error must be zero or more");
    }
    if (!(options_.targetFps > 0)) throw InputError("operating point: the target frame rate must be positive");
    options_.smoothing = std::clamp(options_.smoothing, 1e-3, 1.0);
    front_ = paretoFront(points);
    current_ = bestFitting(budgetSeconds());
}

void OperatingPointController::setTargetFps(double fps) {
    if (!(fps > 0)) throw InputError("operating point: the target frame rate must be positive");
    options_.targetFps = fps;
    overBudget_ = underBudget_ = 0;
}

size_t OperatingPointController::bestFitting(double budget) const {
    // front_ is sorted by frame time and error falls along it: the last fitting point is the
    // most accurate one that fits.
    size_t best = 0;
    for (size_t i = 0; i < front_.size(); ++i)
        if (front_[i].frameSeconds * ratio_ <= budget) best = i;
    return best;
}

bool OperatingPointController::observe(double measured, bool moving) {
    if (!(measured > 0) || !std::isfinite(measured)) return false;  // no information
    const double sample = measured / front_[current_].frameSeconds;
    ratio_ = ratio_ * (1 - options_.smoothing) + sample * options_.smoothing;

    const double budget = budgetSeconds();
    overBudget_ = measured > budget * (1 + options_.tolerance) ? overBudget_ + 1 : 0;
    const size_t up = bestFitting(budget * (1 - options_.headroom));
    // Motion never counts towards a step up: refinement waits for a still view.
    underBudget_ = up > current_ && !moving ? underBudget_ + 1 : 0;

    const bool downNow = moving && overBudget_ >= 1 && current_ > 0;
    if (hold_ > 0 && !downNow) {
        --hold_;
        return false;
    }
    size_t next = current_;
    if ((overBudget_ >= options_.downFrames || downNow) && current_ > 0) {
        // Down to the most accurate point that fits the budget by the current ratio, but at
        // least one step, since the current one demonstrably does not.
        next = std::min(current_ - 1, bestFitting(budget));
    } else if (underBudget_ >= options_.upFrames) {
        next = up;
    }
    if (next == current_) return false;
    current_ = next;
    overBudget_ = underBudget_ = 0;
    hold_ = options_.holdFrames;
    ++changes_;
    return true;
}

}  // namespace rtwall
