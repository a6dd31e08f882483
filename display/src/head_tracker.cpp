// The tracked head in wall coordinates: room transform, one-euro filter, constant-velocity
// prediction and the timeout. Plain code; the socket is in tracker_receiver.cpp.
#include <rtwall/tracking.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace rtwall {

namespace {

using Mat3 = std::array<double, 9>;
using Vec3 = std::array<double, 3>;

Mat3 multiply(const Mat3& a, const Mat3& b) {
    Mat3 m{};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) m[3 * r + c] = a[3 * r] * b[c] + a[3 * r + 1] * b[3 + c] + a[3 * r + 2] * b[6 + c];
    return m;
}

Mat3 rotationAbout(int axis, double degrees) {
    // Exact zeros and ones at multiples of 90 degrees: a room turned by [-90, 0, 0] maps whole
    // millimetres to the very metres a static config would give.
    const double a = std::remainder(degrees, 360.0);
    double c = std::cos(a * std::numbers::pi / 180.0), s = std::sin(a * std::numbers::pi / 180.0);
    if (a == 0) c = 1, s = 0;
    else if (a == 90) c = 0, s = 1;
    else if (a == -90) c = 0, s = -1;
    else if (a == 180 || a == -180) c = -1, s = 0;
    switch (axis) {
    case 0: return {1, 0, 0, 0, c, -s, 0, s, c};
    case 1: return {c, 0, s, 0, 1, 0, -s, 0, c};
    default: return {c, -s, 0, s, c, 0, 0, 0, 1};
    }
}

Float3 toFloat(const Vec3& v) { return {float(v[0]), float(v[1]), float(v[2])}; }

}  // namespace

Vec3 RoomTransform::direction(const Vec3& p) const {
    const Mat3& r = rotation;
    return {r[0] * p[0] + r[1] * p[1] + r[2] * p[2], r[3] * p[0] + r[4] * p[1] + r[5] * p[2], r[6] * p[0] + r[7] * p[1] + r[8] * p[2]};
}

Vec3 RoomTransform::point(const Vec3& p) const {
    const Vec3 d = direction({p[0] * scale, p[1] * scale, p[2] * scale});
    return {d[0] + translate[0], d[1] + translate[1], d[2] + translate[2]};
}

RoomTransform roomTransform(const TrackingConfig& c) {
    RoomTransform t;
    // About x first, then y, then z (as a scene's `rotate`).
    t.rotation = multiply(rotationAbout(2, c.roomRotate[2]), multiply(rotationAbout(1, c.roomRotate[1]), rotationAbout(0, c.roomRotate[0])));
    t.scale = c.roomScale;
    t.translate = c.roomTranslate;
    return t;
}

HeadPose headPoseOf(const DTrackBody& body, const RoomTransform& room) {
    const Mat3& r = body.rotation;
    HeadPose h;
    h.position = toFloat(room.point(body.position));
    h.right = toFloat(room.direction({r[0], r[3], r[6]}));  // the body's x axis: its rotation's first column
    h.up = toFloat(room.direction({r[1], r[4], r[7]}));
    return h;
}

OneEuroFilter::OneEuroFilter(double minCutoff, double beta, double derivativeCutoff)
    : minCutoff_(minCutoff), beta_(beta), derivativeCutoff_(derivativeCutoff) {}

double OneEuroFilter::operator()(double x, double t) {
    if (!primed_) {
        primed_ = true;
        value_ = x;
        derivative_ = 0;
        time_ = t;
        return x;
    }
    const double dt = t - time_;
    if (!(dt > 0)) return value_;  // a repeated or out-of-order time: nothing to learn from it
    auto alpha = [dt](double cutoff) { return 1.0 / (1.0 + 1.0 / (2.0 * std::numbers::pi * cutoff * dt)); };
    derivative_ += alpha(derivativeCutoff_) * ((x - value_) / dt - derivative_);
    value_ += alpha(minCutoff_ + beta_ * std::fabs(derivative_)) * (x - value_);
    time_ = t;
    return value_;
}

HeadTracker::HeadTracker(const TrackingConfig& config)
    : config_(config), room_(roomTransform(config)), prediction_(config.predictionMs * 1e-3),
      filters_{OneEuroFilter(config.minCutoff, config.beta, config.derivativeCutoff),
               OneEuroFilter(config.minCutoff, config.beta, config.derivativeCutoff),
               OneEuroFilter(config.minCutoff, config.beta, config.derivativeCutoff)} {
    last_.position = {0, 0, 0};
}

void HeadTracker::countDropped(const std::string& why) {
    ++packets_;
    ++dropped_;
    lastError_ = why;
}

bool HeadTracker::add(const DTrackFrame& frame, double time) {
    ++packets_;
    const DTrackBody* body = frame.body(config_.headBody);
    if (!body || body->quality < 0) return false;
    HeadPose pose = headPoseOf(*body, room_);
    if (seen_ && time - lastTime_ > config_.timeoutMs * 1e-3) {
        // Back after a gap: the filter and the velocity start afresh rather than smear over it.
        for (OneEuroFilter& f : filters_) f.reset();
        recent_.clear();
    }
    Vec3 p{pose.position.x, pose.position.y, pose.position.z};
    if (config_.filter == TrackingFilter::OneEuro) {
        for (int i = 0; i < 3; ++i) p[i] = filters_[size_t(i)](p[i], time);
        pose.position = toFloat(p);
    }
    if (!recent_.empty() && time <= recent_.back().time) recent_.clear();  // the clock went back: start again
    recent_.push_back({time, p});
    // Keep the window, and at least the pose before this one.
    while (recent_.size() > 2 && recent_[1].time < time - kVelocityWindow) recent_.erase(recent_.begin());
    last_ = pose;
    lastTime_ = time;
    seen_ = true;
    return true;
}

// Least-squares slope of the recent positions over time.
Vec3 HeadTracker::velocity() const {
    if (recent_.size() < 2) return {0, 0, 0};
    double mt = 0;
    for (const Sample& s : recent_) mt += s.time;
    mt /= double(recent_.size());
    Vec3 v{};
    double stt = 0;
    for (const Sample& s : recent_) stt += (s.time - mt) * (s.time - mt);
    if (!(stt > 0)) return v;
    for (int i = 0; i < 3; ++i) {
        double mp = 0, stp = 0;
        for (const Sample& s : recent_) mp += s.position[size_t(i)];
        mp /= double(recent_.size());
        for (const Sample& s : recent_) stp += (s.time - mt) * (s.position[size_t(i)] - mp);
        v[size_t(i)] = stp / stt;
    }
    return v;
}

TrackerState HeadTracker::at(double time) const {
    TrackerState s;
    s.packets = packets_;
    s.dropped = dropped_;
    s.lastError = lastError_;
    s.seen = seen_;
    if (!seen_) return s;
    s.age = time - lastTime_;
    s.stale = s.age > config_.timeoutMs * 1e-3;
    s.head = last_;
    if (s.stale || prediction_ <= 0) return s;
    const Vec3 v = velocity();
    s.velocity = toFloat(v);
    const double ahead = std::max(0.0, s.age) + prediction_;
    s.head.position = toFloat({last_.position.x + v[0] * ahead, last_.position.y + v[1] * ahead, last_.position.z + v[2] * ahead});
    return s;
}

std::string describeTracker(const TrackerState& s) {
    char buf[200];
    if (!s.seen)
        std::snprintf(buf, sizeof buf, "tracker: no head yet (%llu packets, %llu dropped)", (unsigned long long)s.packets,
                      (unsigned long long)s.dropped);
    else if (s.stale)
        std::snprintf(buf, sizeof buf, "tracker: no head for %.1f s, holding the last pose", s.age);
    else
        std::snprintf(buf, sizeof buf, "tracker: head at (%.3f, %.3f, %.3f) m, %.0f ms old, %llu dropped", s.head.position.x,
                      s.head.position.y, s.head.position.z, s.age * 1e3, (unsigned long long)s.dropped);
    return buf;
}

}  // namespace rtwall
