// Fly and orbit navigation, bookmarks and camera-path recording: plain state fed with the
// input the presenter collected, so it is tested without a window.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes only

#include <rtwall/display.h>
#include <rtwall/double3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <numbers>
#include <sstream>

namespace rtwall {

namespace {
using V = Double3;  // the pose in double: small steps far from the origin add up without drifting
// Rodrigues' rotation of p about unit axis k.
V rotate(V p, V k, double rad) {
    const double c = std::cos(rad), s = std::sin(rad);
    return p * c + k.cross(p) * s + k * (k.dot(p) * (1 - c));
}
constexpr double kRadPerPixel = 0.005;
constexpr double kMaxPitch = 1.5;  // radians from the horizon: never quite straight up or down
}  // namespace

Navigator::Navigator(const ViewPose& start, float sceneScale) : pose_(start), speed_(std::max(sceneScale, 1e-3f)) {}

bool Navigator::hasBookmark(int slot) const { return slot >= 0 && slot < 10 && hasBookmark_[size_t(slot)]; }

bool Navigator::update(const InputState& in, double dt) {
    bool changed = false;
    for (size_t i = 0; i < in.keysPressed.size(); ++i) {
        const int key = in.keysPressed[i], mods = i < in.modsPressed.size() ? in.modsPressed[i] : 0;
        if (key >= GLFW_KEY_1 && key <= GLFW_KEY_9) {
            const size_t slot = size_t(key - GLFW_KEY_0);
            if (mods & GLFW_MOD_CONTROL) {
                bookmarks_[slot] = pose_;
                hasBookmark_[slot] = true;
            } else if (hasBookmark_[slot]) {
                pose_ = bookmarks_[slot];
                changed = true;
            }
        } else if (key == GLFW_KEY_TAB) {
            mode_ = mode_ == Mode::Fly ? Mode::Orbit : Mode::Fly;
        } else if (key == GLFW_KEY_R) {
            recording_ = !recording_;
            if (recording_) path_.clear();
        }
    }

    const V up = V::of(pose_.up).normalized();
    V pos = V::of(pose_.position), at = V::of(pose_.lookAt);
    V fwd = at - pos;
    const double dist = fwd.length();
    fwd = fwd.normalized();
    const V right = fwd.cross(up).normalized();
    const bool picking = in.leftDown && (in.clickMods & GLFW_MOD_CONTROL);
    const double dx = picking ? 0.0 : in.mouseDx, dy = picking ? 0.0 : in.mouseDy;
    // Turns `vec` up or down by `delta` radians of elevation, never past kMaxPitch: asin alone
    // cannot tell a vector that went over the pole from one that did not, so clamp the angle.
    auto pitched = [&](V vec, V axis, double delta, double sign) {
        const double e = std::asin(std::clamp(vec.normalized().dot(up), -1.0, 1.0));
        const double target = std::clamp(e + delta, -kMaxPitch, kMaxPitch);
        return rotate(vec, axis, sign * (target - e));
    };
    if (mode_ == Mode::Fly) {
        V move{0, 0, 0};
        auto down = [&](int k) { return in.keyDown[size_t(k)]; };
        if (down(GLFW_KEY_W)) move = move + fwd;
        if (down(GLFW_KEY_S)) move = move - fwd;
        if (down(GLFW_KEY_D)) move = move + right;
        if (down(GLFW_KEY_A)) move = move - right;
        if (down(GLFW_KEY_E)) move = move + up;
        if (down(GLFW_KEY_Q)) move = move - up;
        const double fast = down(GLFW_KEY_LEFT_SHIFT) ? 4.0 : 1.0;
        if (move.dot(move) > 0) {
            const V step = move.normalized() * (double(speed_) * fast * dt);
            pos = pos + step;
            at = at + step;
            changed = true;
        }
        if (dx != 0 || dy != 0) {
            // Mouse look: the view direction turns about the camera's position.
            V dir = rotate(at - pos, up, -dx * kRadPerPixel);
            dir = pitched(dir, dir.cross(up).normalized(), -dy * kRadPerPixel, 1.0);
            at = pos + dir;
            changed = true;
        }
    } else {
        if (dx != 0 || dy != 0) {
            // Orbit: the camera turns about the look-at point.
            V off = rotate(pos - at, up, -dx * kRadPerPixel);
            off = pitched(off, (off * -1.0).cross(up).normalized(), dy * kRadPerPixel, -1.0);
            pos = at + off;
            changed = true;
        }
        double zoom = in.scroll;
        if (in.keyDown[GLFW_KEY_W]) zoom += 2.0 * dt;
        if (in.keyDown[GLFW_KEY_S]) zoom -= 2.0 * dt;
        if (zoom != 0 && dist > 0) {
            const double d = std::max(dist * std::pow(0.9, zoom), 1e-3 * double(speed_));
            pos = at - fwd * d;
            changed = true;
        }
    }
    pose_.position = pos.toFloat3();
    pose_.lookAt = at.toFloat3();
    if (recording_) path_.push_back(pose_);
    return changed;
}

bool Navigator::updateWand(const Wand& w, double dt) {
    if ((w.x == 0 && w.y == 0) || !(dt > 0)) return false;
    const V up = V::of(pose_.up).normalized();
    V pos = V::of(pose_.position), at = V::of(pose_.lookAt);
    // Joystick right turns right: clockwise seen from above, a negative angle about up.
    const double turn = -w.x * w.turnDegrees * std::numbers::pi / 180.0 * dt;
    if (mode_ == Mode::Fly) {
        const V step = V::of(w.direction).normalized() * (w.y * w.speed * dt);
        pos = pos + step;
        at = at + step;
        at = pos + rotate(at - pos, up, turn);
    } else {
        const V c = V::of(w.centre);
        pos = c + rotate(pos - c, up, turn);
        at = c + rotate(at - c, up, turn);
        // Towards the centre (y > 0) or away; the view direction stays.
        const V toCentre = c - pos;
        const double dist = toCentre.length();
        if (dist > 0) {
            const double step = std::min(w.y * w.speed * dt, dist - 1e-3 * double(speed_));
            if (step > 0 || w.y < 0) {
                const V move = toCentre * (std::min(step, dist) / dist);
                pos = pos + move;
                at = at + move;
            }
        }
    }
    pose_.position = pos.toFloat3();
    pose_.lookAt = at.toFloat3();
    if (recording_) path_.push_back(pose_);
    return true;
}


}  // namespace rtwall
