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

using Quat = std::array<double, 4>;

Quat quaternionOf(const Mat3& m) {
    // Shepperd's method: from the largest of w, x, y, z, so no division by a small number.
    const double tr = m[0] + m[4] + m[8];
    Quat q;
    if (tr > 0) {
        const double s = 2 * std::sqrt(1 + tr);
        q = {0.25 * s, (m[7] - m[5]) / s, (m[2] - m[6]) / s, (m[3] - m[1]) / s};
    } else if (m[0] > m[4] && m[0] > m[8]) {
        const double s = 2 * std::sqrt(1 + m[0] - m[4] - m[8]);
        q = {(m[7] - m[5]) / s, 0.25 * s, (m[1] + m[3]) / s, (m[2] + m[6]) / s};
    } else if (m[4] > m[8]) {
        const double s = 2 * std::sqrt(1 + m[4] - m[0] - m[8]);
        q = {(m[2] - m[6]) / s, (m[1] + m[3]) / s, 0.25 * s, (m[5] + m[7]) / s};
    } else {
        const double s = 2 * std::sqrt(1 + m[8] - m[0] - m[4]);
        q = {(m[3] - m[1]) / s, (m[2] + m[6]) / s, (m[5] + m[7]) / s, 0.25 * s};
    }
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (double& c : q) c /= n;
    return q;
}

Mat3 rotationOf(const Quat& q) {
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
            2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

Quat slerp(const Quat& a, const Quat& b0, double t) {
    double d = a[0] * b0[0] + a[1] * b0[1] + a[2] * b0[2] + a[3] * b0[3];
    Quat b = b0;
    if (d < 0) {  // the same turn on a's side of the sphere
        for (double& c : b) c = -c;
        d = -d;
    }
    double wa = 1 - t, wb = t;
    if (d < 0.9995) {
        const double theta = std::acos(std::min(1.0, d)), s = std::sin(theta);
        wa = std::sin((1 - t) * theta) / s;
        wb = std::sin(t * theta) / s;
    }
    Quat q{};
    double n = 0;
    for (size_t i = 0; i < 4; ++i) n += (q[i] = wa * a[i] + wb * b[i]) * q[i];
    n = std::sqrt(n);
    for (double& c : q) c /= n;
    return q;
}

OneEuroRotationFilter::OneEuroRotationFilter(double minCutoff, double beta, double derivativeCutoff)
    : minCutoff_(minCutoff), beta_(beta), derivativeCutoff_(derivativeCutoff) {}

Quat OneEuroRotationFilter::operator()(const Quat& q, double t) {
    if (!primed_) {
        primed_ = true;
        value_ = q;
        speed_ = 0;
        time_ = t;
        return q;
    }
    const double dt = t - time_;
    if (!(dt > 0)) return value_;
    auto alpha = [dt](double cutoff) { return 1.0 / (1.0 + 1.0 / (2.0 * std::numbers::pi * cutoff * dt)); };
    // The angle from the filtered orientation to the new one, per second: the speed the cutoff follows.
    const double d = std::fabs(value_[0] * q[0] + value_[1] * q[1] + value_[2] * q[2] + value_[3] * q[3]);
    const double angle = 2 * std::acos(std::min(1.0, d));
    speed_ += alpha(derivativeCutoff_) * (angle / dt - speed_);
    value_ = slerp(value_, q, alpha(minCutoff_ + beta_ * speed_));
    time_ = t;
    return value_;
}

HeadTracker::HeadTracker(const TrackingConfig& config)
    : config_(config), room_(roomTransform(config)), prediction_(config.predictionMs * 1e-3),
      filters_{OneEuroFilter(config.minCutoff, config.beta, config.derivativeCutoff),
               OneEuroFilter(config.minCutoff, config.beta, config.derivativeCutoff),
               OneEuroFilter(config.minCutoff, config.beta, config.derivativeCutoff)},
      headRotation_(config.minCutoff, config.beta, config.derivativeCutoff),
      wandRotation_(config.minCutoff, config.beta, config.derivativeCutoff),
      wandFilters_{OneEuroFilter(config.minCutoff, config.beta, config.derivativeCutoff),
                   OneEuroFilter(config.minCutoff, config.beta, config.derivativeCutoff),
                   OneEuroFilter(config.minCutoff, config.beta, config.derivativeCutoff)} {
    last_.position = {0, 0, 0};
}

double HeadTracker::sampleTime(const DTrackFrame& frame, double time, std::optional<double> arrivalUtc) {
    if (!frame.timestamp) {
        latency_.reset();
        return time;
    }
    const double stamp = *frame.timestamp;
    if (arrivalUtc) {
        const double transit = std::remainder(*arrivalUtc - stamp, 86400.0);  // across midnight too
        if (transit >= 0 && transit < 1) {
            latency_ = transit;
            return time - transit;
        }
    }
    latency_.reset();
    // Clocks that do not agree: the fastest transit so far is taken as none. The offset may creep
    // up by 100 ppm of the time passed, more than two quartz clocks drift apart, so a drift
    // cannot leave it behind for good.
    if (!clockOffset_ || stamp < lastStamp_) clockOffset_ = time - stamp;
    else clockOffset_ = std::min(*clockOffset_ + 1e-4 * (stamp - lastStamp_), time - stamp);
    lastStamp_ = stamp;
    return stamp + *clockOffset_;
}

void HeadTracker::countDropped(const std::string& why) {
    ++packets_;
    ++dropped_;
    lastError_ = why;
}

bool HeadTracker::add(const DTrackFrame& frame, double arrival, std::optional<double> arrivalUtc) {
    ++packets_;
    const double time = sampleTime(frame, arrival, arrivalUtc);
    const bool filtered = config_.filter == TrackingFilter::OneEuro;
    if (const DTrackFlystick* f = config_.flystick >= 0 ? frame.flystick(config_.flystick) : nullptr) {
        if (wand_.seen && time - wandTime_ > config_.timeoutMs * 1e-3) {
            for (OneEuroFilter& filter : wandFilters_) filter.reset();
            wandRotation_.reset();
            // A stale wand's buttons counted as up: its readers saw them let go, so say so, and a
            // button still down now is pressed anew.
            recordButtonChanges({});
            wand_.buttons.clear();
        }
        recordButtonChanges(f->buttons);
        wand_.buttons = f->buttons;
        wand_.controllers = f->controllers;
        wand_.visible = f->pose.quality >= 0;
        if (wand_.visible) {
            Vec3 p = room_.point(f->pose.position);
            Mat3 r = multiply(room_.rotation, f->pose.rotation);
            if (filtered) {
                for (int i = 0; i < 3; ++i) p[size_t(i)] = wandFilters_[size_t(i)](p[size_t(i)], time);
                r = rotationOf(wandRotation_(quaternionOf(r), time));
            }
            wand_.position = toFloat(p);
            wand_.rotation = r;
            const std::array<double, 3>& a = config_.wandDirection;
            Vec3 d{r[0] * a[0] + r[1] * a[1] + r[2] * a[2], r[3] * a[0] + r[4] * a[1] + r[5] * a[2], r[6] * a[0] + r[7] * a[1] + r[8] * a[2]};
            const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (n > 0) wand_.direction = toFloat({d[0] / n, d[1] / n, d[2] / n});
            wand_.seen = true;
        }
        wandTime_ = time;  // buttons alone also keep it alive: a flystick out of sight still clicks
    }
    const DTrackBody* body = frame.body(config_.headBody);
    if (!body || body->quality < 0) return false;
    HeadPose pose = headPoseOf(*body, room_);
    if (seen_ && time - lastTime_ > config_.timeoutMs * 1e-3) {
        // Back after a gap: the filter and the velocity start afresh rather than smear over it.
        for (OneEuroFilter& f : filters_) f.reset();
        headRotation_.reset();
        recent_.clear();
    }
    Vec3 p{pose.position.x, pose.position.y, pose.position.z};
    if (filtered) {
        for (int i = 0; i < 3; ++i) p[size_t(i)] = filters_[size_t(i)](p[size_t(i)], time);
        pose.position = toFloat(p);
        // The orientation too: a jittering head turns the eyes' baseline, which shows as vertical
        // parallax in stereo.
        const Mat3 r = rotationOf(headRotation_(quaternionOf(multiply(room_.rotation, body->rotation)), time));
        pose.right = toFloat({r[0], r[3], r[6]});
        pose.up = toFloat({r[1], r[4], r[7]});
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

// Each button that differs from the last frame's is one event (a button the frame does not
// list is up). Frames come in the order the tracker sent them (VRPN: one per button change), so
// the events keep the order of the presses.
void HeadTracker::recordButtonChanges(const std::vector<bool>& buttons) {
    std::vector<ButtonEvent>& events = wand_.events;
    const std::vector<bool>& before = wand_.buttons;
    for (size_t i = 0; i < std::max(buttons.size(), before.size()); ++i) {
        const bool now = i < buttons.size() && buttons[i], was = i < before.size() && before[i];
        if (now != was) events.push_back({wand_.lastEvent() + 1, int(i), now});
    }
    if (events.size() > WandState::kMaxButtonEvents)
        events.erase(events.begin(), events.end() - std::ptrdiff_t(WandState::kMaxButtonEvents));
}

std::vector<ButtonEvent> WandState::eventsAfter(uint64_t after, uint64_t* lost) const {
    std::vector<ButtonEvent> out;
    for (const ButtonEvent& e : events)
        if (e.seq > after) out.push_back(e);
    if (lost) *lost = out.empty() || out.front().seq <= after + 1 ? 0 : out.front().seq - after - 1;
    return out;
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
    s.latency = latency_;
    s.wand = wand_;
    s.wand.stale = wand_.seen && time - wandTime_ > config_.timeoutMs * 1e-3;
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
    std::string line = buf;
    if (s.seen && !s.stale && s.latency) {
        std::snprintf(buf, sizeof buf, ", measured %.1f ms before arrival", *s.latency * 1e3);
        line += buf;
    }
    if (s.wand.seen)
        line += s.wand.stale ? ", wand lost" : s.wand.visible ? ", wand seen" : ", wand out of sight";
    return line;
}

}  // namespace rtwall
