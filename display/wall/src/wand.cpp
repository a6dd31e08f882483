// The tracked wand (WallInput::handleWand, drawWand): joystick navigation, picking and dragging
// objects or section planes with the wand's ray, and the ray drawn into the eye images. Split
// from wall_input.cpp to keep each file of the wall's input to a few hundred lines.
#include "wall_input.h"

#include <rtwall/wall.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rtwall::wall {

namespace {
using Mat3 = std::array<double, 9>;
Mat3 multiply(const Mat3& a, const Mat3& b) {
    Mat3 m{};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) m[size_t(3 * r + c)] = a[size_t(3 * r)] * b[size_t(c)] + a[size_t(3 * r + 1)] * b[size_t(3 + c)] + a[size_t(3 * r + 2)] * b[size_t(6 + c)];
    return m;
}
// A joystick axis past the dead zone, rescaled so that full deflection stays 1.
double deflection(double value, double deadZone) {
    const double a = std::fabs(value);
    if (!(a > deadZone)) return 0.0;
    return std::copysign(std::min(1.0, (a - deadZone) / (1.0 - deadZone)), value);
}
}  // namespace

void WallInput::handleWand(LiveScene& scene, const TrackerState& tracker, double dt) {
    const TrackingConfig& t = wall_.tracking;
    const WandState& w = tracker.wand;
    if (tracker.seen) head_ = tracker.head;  // the world scale keys scale about it
    uint64_t lost = 0;
    const std::vector<ButtonEvent> events = w.eventsAfter(wandEvents_, &lost);
    wandEvents_ = w.lastEvent();
    if (!w.seen || w.stale) {
        if (wandGrab_) log_("wand: lost, instance " + std::to_string(wandGrab_->instance) + " released");
        wand_.reset();
        wandGrab_.reset();
        wandPlaneStart_.reset();
        return;
    }
    if (lost > 0) log_("wand: " + std::to_string(lost) + " button changes came faster than the frames and were not acted on");
    // Every press since the last frame counts, in order, however short: the mode and home
    // buttons act first, the trigger after the joystick has moved the room.
    for (const ButtonEvent& e : events) {
        if (!options_.interactive || !e.pressed) continue;
        if (e.button == t.buttonMode) {
            nav_->setMode(nav_->mode() == Navigator::Mode::Fly ? Navigator::Mode::Orbit : Navigator::Mode::Fly);
            orbitCentre_.reset();
            log_(nav_->mode() == Navigator::Mode::Fly ? "wand: fly" : "wand: orbit about the scene's centre");
        }
        if (e.button == t.buttonHome) {
            setCamera(base_);
            scale_ = wall_.navigation.scale;  // the start camera is at the configured scale
            scene.setCamera(camera());
            log_("wand: back to the start camera");
        }
    }
    // The joystick moves the room through the scene, then the wand is placed in the moved room.
    WallToWorld map = wallToWorld(wall_.stereo.viewer, nav_->pose(), scale_);
    if (options_.interactive) {
        Navigator::Wand nw;
        nw.x = deflection(w.controller(t.joystickX), t.deadZone);
        nw.y = deflection(w.controller(t.joystickY), t.deadZone);
        nw.direction = map.direction(w.direction);
        nw.speed = t.flySpeed * scale_;  // fly_speed is metres of the room a second
        nw.turnDegrees = t.turnSpeed;
        if (nav_->mode() == Navigator::Mode::Orbit && (nw.x != 0 || nw.y != 0) && !orbitCentre_) {
            const Bounds3 b = scene.desc().worldBounds();
            orbitCentre_ = b.empty() ? nav_->pose().lookAt
                                     : Float3{(b.lo.x + b.hi.x) * 0.5f, (b.lo.y + b.hi.y) * 0.5f, (b.lo.z + b.hi.z) * 0.5f};
        }
        if (orbitCentre_) nw.centre = *orbitCentre_;
        if (nav_->updateWand(nw, dt)) {
            scene.setCamera(camera());
            map = wallToWorld(wall_.stereo.viewer, nav_->pose(), scale_);
        }
    }
    WandPose p;
    p.wallPosition = w.position;
    p.wallDirection = w.direction;
    p.wallRotation = w.rotation;
    p.origin = map.point(w.position);
    p.direction = map.direction(w.direction);
    // The wall's axes in the world are the columns of the room's turn.
    const Mat3 axes{map.x.x, map.y.x, map.z.x, map.x.y, map.y.y, map.z.y, map.x.z, map.y.z, map.z.z};
    p.rotation = multiply(axes, w.rotation);
    p.buttons = w.buttons;
    p.controllers = w.controllers;
    p.length = kWandRayLength * float(scale_);

    // The trigger's presses and releases in order: a click shorter than a frame picks (or sets a
    // measure point) and lets go again; several clicks act as many times.
    for (const ButtonEvent& e : events) {
        if (e.button != t.buttonPick) continue;
        if (e.pressed && options_.interactive && w.visible) wandPress(scene, p);
        else if (!e.pressed) wandRelease(scene);
    }
    // What the events may have missed (more changes than kept): the trigger's state now.
    if ((wandGrab_ || wandPlaneStart_) && !w.button(t.buttonPick)) wandRelease(scene);
    if (wandPlaneStart_ && activeSection_ < 0) wandRelease(scene);
    if ((wandGrab_ || wandPlaneStart_) && w.visible) {
        dragHeld(scene, p);
    } else if (w.visible) {
        if (const std::optional<PickResult> hit = scene.pickRay(p.origin, p.direction)) p.length = hit->t;
    }
    wand_ = p;
}

// The trigger pressed with the wand at `p`: a measure point, the selected section plane taken,
// or the object it points at picked.
void WallInput::wandPress(LiveScene& scene, const WandPose& p) {
    if (measuring_) {
        measureHit(scene, scene.pickRay(p.origin, p.direction), p.origin, p.direction);
    } else if (activeSection_ >= 0) {
        // A selected section plane: the trigger holds the plane, not an object (Shift+C until
        // none is selected gives the trigger back to objects).
        wandPlaneStart_ = scene.desc().sections[size_t(activeSection_)];
        wandGrabStart_ = p;
        log_("wand: holds section " + std::to_string(activeSection_));
    } else {
        wandGrab_ = scene.pickRay(p.origin, p.direction);
        if (wandGrab_) {
            wandGrabStart_ = p;
            wandGrabTransform_ = scene.desc().instances[wandGrab_->instance].transform;
            char line[128];
            std::snprintf(line, sizeof line, "wand: picked instance %u at distance %.2f", wandGrab_->instance, double(wandGrab_->t));
            const std::string part = scene.desc().partPath(scene.desc().instances[wandGrab_->instance].part);
            log_(part.empty() ? std::string(line) : std::string(line) + ", part '" + part + "'");
        }
    }
}

// The trigger let go: what it held stays where it was put.
void WallInput::wandRelease(LiveScene& scene) {
    if (wandPlaneStart_) {
        log_(activeSection_ < 0 ? "wand: section released" : "wand: released " + sectionLine(scene.desc()));
        wandPlaneStart_.reset();
    }
    if (wandGrab_) {
        log_("wand: released instance " + std::to_string(wandGrab_->instance));
        wandGrab_.reset();
    }
}

// Rigidly with the wand: the held object (or plane) is moved by the wand's motion since the
// pick, motion = now * start^-1 (world), applied after its transform at the pick.
void WallInput::dragHeld(LiveScene& scene, WandPose& p) {
    const WandPose& s = wandGrabStart_;
    const Mat3& r1 = p.rotation;
    const Mat3& r0 = s.rotation;
    const Mat3 r0t{r0[0], r0[3], r0[6], r0[1], r0[4], r0[7], r0[2], r0[5], r0[8]};
    const Mat3 r = multiply(r1, r0t);
    const std::array<double, 3> p0{s.origin.x, s.origin.y, s.origin.z}, p1{p.origin.x, p.origin.y, p.origin.z};
    Transform motion;
    for (int i = 0; i < 3; ++i) {
        const size_t row = size_t(3 * i);
        for (int j = 0; j < 3; ++j) motion.m[size_t(4 * i + j)] = r[row + size_t(j)];
        motion.m[size_t(4 * i + 3)] = p1[size_t(i)] - (r[row] * p0[0] + r[row + 1] * p0[1] + r[row + 2] * p0[2]);
    }
    if (wandPlaneStart_) {
        // The plane's point moves with the wand and its normal turns with it; the plane
        // stays where it was put when the trigger is let go.
        SectionPlane plane = *wandPlaneStart_;
        const Float3 q = plane.point, n = plane.normal;
        plane.point = {float(motion.m[0] * q.x + motion.m[1] * q.y + motion.m[2] * q.z + motion.m[3]),
                       float(motion.m[4] * q.x + motion.m[5] * q.y + motion.m[6] * q.z + motion.m[7]),
                       float(motion.m[8] * q.x + motion.m[9] * q.y + motion.m[10] * q.z + motion.m[11])};
        plane.normal = {float(r[0] * n.x + r[1] * n.y + r[2] * n.z), float(r[3] * n.x + r[4] * n.y + r[5] * n.z),
                        float(r[6] * n.x + r[7] * n.y + r[8] * n.z)};
        setSection(scene, uint32_t(activeSection_), plane);
        if (const std::optional<PickResult> hit = scene.pickRay(p.origin, p.direction)) p.length = hit->t;
    } else {
        scene.setInstanceTransform(wandGrab_->instance, motion * wandGrabTransform_);
        p.dragging = wandGrab_->instance;
        p.length = wandGrab_->t;
    }
}

void WallInput::drawWand(WallFrame& frame, const HeadPose& head) const {
    frame.paints.clear();
    if (!wand_ || !wall_.tracking.wandRay) return;
    const Float3 a = wand_->wallPosition, d = wand_->wallDirection;
    const float metres = wand_->length / float(scale_);  // the length is in scene units
    const Float3 b{a.x + d.x * metres, a.y + d.y * metres, a.z + d.z * metres};
    // A frame the GL presenter warps has no eye images here: it paints the ray after its warp.
    const bool gpu = !frame.warps.empty();
    const int width = gpu ? frame.warps[0].image->width : frame.left.width;
    const int height = gpu ? frame.warps[0].image->height : frame.left.height;
    if (wall_.stereo.mode == StereoMode::None) {
        wandRayPaints(wall_, head, -1, a, b, width, height, frame.paints);
    } else {
        wandRayPaints(wall_, head, 0, a, b, width, height, frame.paints);
        wandRayPaints(wall_, head, 1, a, b, width, height, frame.paints);
    }
    if (gpu) return;
    applyPaints(frame.paints, 0, frame.left);
    applyPaints(frame.paints, 1, frame.right);
    frame.paints.clear();
}

}  // namespace rtwall::wall
