#include "wall_input.h"

#include <rtwall/vec.h>
#include <rtwall/wall.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

namespace rtwall::wall {

namespace {
ViewPose poseOf(const CameraDesc& c) { return {c.position, c.lookAt, c.up, c.fovY}; }
CameraDesc cameraOf(const CameraDesc& base, const ViewPose& p) {
    CameraDesc c = base;
    c.position = p.position;
    c.lookAt = p.lookAt;
    c.up = p.up;
    c.fovY = p.fovY;
    return c;
}
}  // namespace

WallInput::WallInput(const WallConfig& wall, const CameraDesc& start, const Options& options,
                     std::function<void(const std::string&)> log)
    : wall_(wall), base_(start), options_(options), log_(std::move(log)), scale_(wall.navigation.scale),
      head_(staticHead(wall.stereo)) {
    present_.stages = options.stages;
    if (options.console) {
        // The wall's aspect, 640 pixels wide at most: clicks map to the wall by one scale.
        const int w = std::min(640, wall_.width), h = std::clamp(int(std::lround(double(w) * wall_.height / wall_.width)), 120, 960);
        console_ = singleScreenWall(w, h);
        console_.name = "rtwall master: " + wall_.name;
        console_.vsync = false;  // the nodes swap in step; the console must not hold the master's loop
    }
    if (options.forceHeadless) whyHeadless_ = "--headless";
    else gl_ = GlPresenter::open(options.console ? console_ : wall_, {}, &whyHeadless_);
    if (!gl_ && options.perScreenImages && !options.console) headless_ = std::make_unique<HeadlessPresenter>(wall_, options.outDir);
    const Float3 d = start.position - start.lookAt;
    nav_ = std::make_unique<Navigator>(poseOf(start), std::max(0.1f, length(d)));
    // A flystick flies by default, as in every VR wall; its mode button (or Tab) orbits.
    if (wall_.tracking.enabled && wall_.tracking.flystick >= 0) nav_->setMode(Navigator::Mode::Fly);
    if (gl_ && options.console)
        log_("wall '" + wall_.name + "': on its display nodes; this PC shows a console window (" + gl_->renderer() +
             ") with their status; the wall's keys work there (H status, Tab fly/orbit, 1-9 bookmarks, [ ] world scale, Esc quits, ...)");
    else if (gl_)
        log_("wall '" + wall_.name + "': " + std::to_string(wall_.screens.size()) + " window" +
             (wall_.screens.size() == 1 ? "" : "s") + " (" + gl_->renderer() +
             "); keys: H status, T tile owners, Tab fly/orbit, 1-9 bookmarks (Ctrl+digit stores), [ ] world scale, R record, Ctrl+drag "
             "moves an object (and picks its part: X hides, I isolates, G highlights it, U shows all), M measure, C section "
             "plane (Shift+C next, V on/off, F flip, PgUp/PgDn move, arrows turn, Del remove), Esc quits");
    else
        log_("wall '" + wall_.name + "': headless (" + whyHeadless_ + ")");
}

WallInput::~WallInput() = default;

CameraDesc WallInput::camera() const { return cameraOf(base_, nav_->pose()); }

CameraDesc WallInput::viewCamera(const EyeWindow& window) const {
    CameraDesc c = camera();
    // Off-axis: the eye sees the wall's physical rectangle as a projection window. The wall frame
    // is carried into the world by the navigation pose (wall x, y, z = camera right, up, back; the
    // config's viewer = the camera position, so a tracked head moves within a room that stays
    // put in the scene; 1 metre = scale_ world units): see eyeWindowInWorld.
    const EyeWindow w = eyeWindowInWorld(window, wall_.stereo.viewer, nav_->pose(), scale_);
    const Float3 f = c.lookAt - c.position;
    c.position = w.eye;
    c.lookAt = w.eye + f;  // unused by the window; kept sensible
    c.window = ProjectionWindow{w.lowerLeft, w.right, w.up};
    return c;
}

RoomToWorld WallInput::roomToWorld() const { return wallToWorld(wall_.stereo.viewer, nav_->pose(), scale_); }

void WallInput::setCamera(const CameraDesc& c) { nav_->setPose(poseOf(c)); }

void WallInput::setNavigationScale(double scale) {
    // The config's range: a pose of floats carries nothing finer or coarser.
    scale = std::clamp(scale, 1e-6, 1e6);
    if (scale == scale_) return;
    // About the head: the point between the eyes stays where it is in the scene, so the world
    // grows or shrinks around the viewer instead of running away from them.
    nav_->setPose(rescaledPose(nav_->pose(), wall_.stereo.viewer, scale_, scale, head_.position));
    scale_ = scale;
    char line[96];
    std::snprintf(line, sizeof line, "navigation: scale %.4g scene units per metre ([ and ] change it)", scale_);
    log_(line);
    refreshStatus();
}

Camera WallInput::pickCamera(double wallX, double wallY) const {
    if (pickCamera_)
        if (std::optional<Camera> c = pickCamera_(wallX, wallY)) return std::move(*c);
    return Camera(camera(), wall_.width, wall_.height);
}

std::optional<PickResult> WallInput::pick(LiveScene& scene, double wallX, double wallY) {
    return scene.pick(pickCamera(wallX, wallY), wallX, wallY);
}

namespace {
std::string pointText(const std::array<double, 3>& p) {
    char text[128];
    std::snprintf(text, sizeof text, "(%.6f, %.6f, %.6f)", p[0], p[1], p[2]);
    return text;
}
}  // namespace

void WallInput::setMeasuring(bool on) {
    if (on == measuring_) return;
    measuring_ = on;
    measurement_.reset();
    grabbed_.reset();
    log_(on ? "measure: on (Ctrl+click point A, then B; M or Esc leaves)" : "measure: off");
    updateOverlay();
    statusImage_ = {};
    refreshStatus();
}

bool WallInput::measurePick(LiveScene& scene, double wallX, double wallY) {
    if (!measuring_) return false;
    const Camera cam = pickCamera(wallX, wallY);
    return measureHit(scene, scene.pick(cam, wallX, wallY), cam.origin(), cam.direction(float(wallX), float(wallY)));
}

// A hit of the ray o + t d (a click's or the wand's) as the next point of the measurement.
bool WallInput::measureHit(LiveScene& scene, const std::optional<PickResult>& hit, Float3 o, Float3 d) {
    const bool newMeasurement = !measurement_ || measurement_->b;
    if (!hit) {
        log_(std::string("measure: nothing under the cursor, point ") + (newMeasurement ? "A" : "B") + " not set");
        return false;
    }
    // The hit point again from the ray, in double, with the rebased scene's origin added back:
    // the float t Embree found (a few ulps, ~1e-7 of the distance from the eye) is then the only
    // single-precision error, however far from the file's origin the model lies
    // (docs/design-review.md, "Measuring").
    const std::array<double, 3>& origin = scene.desc().origin;
    const double t = hit->t;
    const std::array<double, 3> p{origin[0] + (double(o.x) + t * double(d.x)), origin[1] + (double(o.y) + t * double(d.y)),
                                  origin[2] + (double(o.z) + t * double(d.z))};
    if (newMeasurement) {
        measurement_ = Measurement{p, std::nullopt, 0.0};
        log_("measure: A " + pointText(p) + ", Ctrl+click B");
    } else {
        // From the file's coordinates: adding an origin of 1e6 rounds by ~1e-10, far below
        // the hit's own error.
        const double dx = p[0] - measurement_->a[0], dy = p[1] - measurement_->a[1], dz = p[2] - measurement_->a[2];
        measurement_->b = p;
        measurement_->distance = std::sqrt(dx * dx + dy * dy + dz * dz);
        kept_.push_back(*measurement_);  // the session's list (the console's, a session file's)
        log_(measureLine());
    }
    refreshStatus();
    return true;
}

std::optional<Measurement> WallInput::measureBetween(LiveScene& scene, double ax, double ay, double bx, double by) {
    // Measure mode's own picks, its state put back after: the same points as two Ctrl+clicks.
    const bool was = measuring_;
    std::optional<Measurement> under = measurement_;
    measuring_ = true;
    measurement_.reset();
    std::optional<Measurement> out;
    if (measurePick(scene, ax, ay) && measurePick(scene, bx, by)) out = measurement_;
    measuring_ = was;
    measurement_ = was ? under : std::nullopt;
    return out;
}

std::string WallInput::measureLine() const {
    if (!measurement_) return "measure: Ctrl+click point A";
    if (!measurement_->b) return "measure: A " + pointText(measurement_->a) + ", Ctrl+click B";
    char distance[64];
    std::snprintf(distance, sizeof distance, ": %.6f scene units", measurement_->distance);
    return "measure: A " + pointText(measurement_->a) + " to B " + pointText(*measurement_->b) + distance;
}

namespace {
std::string quotedList(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& p : v) s += (s.empty() ? "'" : ", '") + p + "'";
    return s;
}
}  // namespace

void WallInput::setPartView(LiveScene& scene, const PartView& view) {
    scene.setPartView(view);
    const PartView& v = scene.partView();
    size_t highlighted = 0;
    for (const InstanceDesc& in : scene.desc().instances) highlighted += in.visibility == Visibility::Highlighted;
    const size_t hidden = scene.hiddenCount();
    std::string line;
    if (!v.isolate.empty()) line += "isolated " + quotedList(v.isolate) + "; ";
    if (!v.hide.empty()) line += "hidden " + quotedList(v.hide) + "; ";
    if (!v.highlight.empty()) line += "highlighted " + quotedList(v.highlight) + "; ";
    if (hidden > 0 || highlighted > 0 || !line.empty())
        line = "parts: " + line + std::to_string(hidden) + " of " + std::to_string(scene.desc().instances.size()) +
               " instances hidden, " + std::to_string(highlighted) + " highlighted (U shows all)";
    if (line != partsLine_ && !line.empty()) log_(line);
    partsLine_ = line;
    updateOverlay();
    refreshStatus();
}

void WallInput::showAllParts(LiveScene& scene) {
    scene.setPartView({}, false);
    if (!partsLine_.empty()) log_("parts: all shown");
    partsLine_.clear();
    updateOverlay();
    statusImage_ = {};
    refreshStatus();
}

// X hides the picked part, I isolates it (again: shows all again), G highlights it (again:
// not), U shows everything.
void WallInput::partKey(LiveScene& scene, int key) {
    if (key == GLFW_KEY_U) return showAllParts(scene);
    if (selected_.empty()) {
        log_("parts: Ctrl+click a part first");
        return;
    }
    PartView v = scene.partView();
    if (key == GLFW_KEY_X) {
        v.hide.push_back(selected_);
        v.highlight.erase(std::remove(v.highlight.begin(), v.highlight.end(), selected_), v.highlight.end());
        selected_.clear();  // it is gone: the next X needs a new pick
    } else if (key == GLFW_KEY_I) {
        v.isolate = v.isolate == std::vector<std::string>{selected_} ? std::vector<std::string>{}
                                                                    : std::vector<std::string>{selected_};
    } else {
        auto it = std::find(v.highlight.begin(), v.highlight.end(), selected_);
        if (it != v.highlight.end()) v.highlight.erase(it);
        else v.highlight.push_back(selected_);
    }
    setPartView(scene, v);
}

bool WallInput::handle(LiveScene& scene, double dt) {
    std::vector<InputState> inputs;
    inputs.swap(injected_);
    if (gl_) {
        InputState in = gl_->poll();
        if (options_.console) {
            // Console pixels to wall pixels: the console has the wall's aspect.
            in.wallX *= double(wall_.width) / console_.width;
            in.wallY *= double(wall_.height) / console_.height;
        }
        inputs.push_back(in);
    }
    for (const InputState& in : inputs)
        if (!apply(scene, in, dt)) return false;
    std::string text = measuring_ ? measureLine() : std::string();
    if (activeSection_ >= 0) text += (text.empty() ? "" : " | ") + sectionLine(scene.desc());
    overlayText_ = std::move(text);
    return true;
}

namespace {

// A slot in use: enabled, or set to anything but the default (a disabled plane from the file).
bool sectionUsed(const SectionPlane& p) { return p.enabled || !(p == SectionPlane{}); }

// v turned by `degrees` about the unit axis a (Rodrigues), in double.
Float3 rotated(const Float3& v, const Float3& a, double degrees) {
    const double r = degrees * 3.14159265358979323846 / 180.0, c = std::cos(r), s = std::sin(r);
    const double ax = a.x, ay = a.y, az = a.z, vx = v.x, vy = v.y, vz = v.z;
    const double d = ax * vx + ay * vy + az * vz;
    const double cx = ay * vz - az * vy, cy = az * vx - ax * vz, cz = ax * vy - ay * vx;
    return {float(vx * c + cx * s + ax * d * (1 - c)), float(vy * c + cy * s + ay * d * (1 - c)),
            float(vz * c + cz * s + az * d * (1 - c))};
}

Float3 unit(const Float3& v) {
    const float l = length(v);
    return l > 0.0f ? Float3{v.x / l, v.y / l, v.z / l} : Float3{0, 0, 0};
}

}  // namespace

void WallInput::setSection(LiveScene& scene, uint32_t index, const SectionPlane& plane) {
    if (index >= uint32_t(kMaxSections))
        throw std::out_of_range("section " + std::to_string(index) + " does not exist (at most " +
                                std::to_string(kMaxSections) + ")");
    scene.setSection(index, plane);
    activeSection_ = int(index);
    updateOverlay();
    refreshStatus();
}

// The section keys: C adds a plane through the point the view looks at, facing along the view
// (what lies before that point is cut away); Shift+C selects the next plane in use (and after
// the last, none); the others act on the selected plane.
void WallInput::sectionKey(LiveScene& scene, int key, int mods) {
    const SceneDesc& desc = scene.desc();
    const bool shift = mods & GLFW_MOD_SHIFT;
    if (key == GLFW_KEY_C && shift) {
        int next = -1;
        for (int i = activeSection_ + 1; i < kMaxSections && next < 0; ++i)
            if (sectionUsed(desc.sections[i])) next = i;
        activeSection_ = next;
        log_(next < 0 ? "section: none selected" : sectionLine(desc));
        updateOverlay();
        refreshStatus();
        return;
    }
    if (key == GLFW_KEY_C) {
        int slot = -1;
        for (int i = 0; i < kMaxSections && slot < 0; ++i)
            if (!sectionUsed(desc.sections[i])) slot = i;
        if (slot < 0) {
            log_("section: all " + std::to_string(kMaxSections) + " planes are in use (Del removes the selected one)");
            return;
        }
        const CameraDesc c = camera();
        SectionPlane p;
        p.enabled = true;
        p.point = c.lookAt;
        p.normal = unit(c.lookAt - c.position);
        if (!(length(p.normal) > 0.0f)) p.normal = {0, 0, -1};
        setSection(scene, uint32_t(slot), p);
        log_(sectionLine(desc));
        return;
    }
    if (activeSection_ < 0) return;
    const bool known = key == GLFW_KEY_V || key == GLFW_KEY_F || key == GLFW_KEY_PAGE_UP || key == GLFW_KEY_PAGE_DOWN ||
                       key == GLFW_KEY_LEFT || key == GLFW_KEY_RIGHT || key == GLFW_KEY_UP || key == GLFW_KEY_DOWN ||
                       key == GLFW_KEY_DELETE;
    if (!known) return;
    SectionPlane p = desc.sections[activeSection_];
    const Float3 n = unit(p.normal);
    if (key == GLFW_KEY_V) p.enabled = !p.enabled;
    if (key == GLFW_KEY_F) p.normal = {-p.normal.x, -p.normal.y, -p.normal.z};
    if (key == GLFW_KEY_PAGE_UP || key == GLFW_KEY_PAGE_DOWN) {
        if (sectionStep_ == 0) {
            const Bounds3 b = desc.worldBounds();
            const double size = b.empty() ? 0.0 : length(b.hi - b.lo);
            sectionStep_ = size > 0 ? size / 100.0 : 0.01;
        }
        const double step = (key == GLFW_KEY_PAGE_UP ? 1.0 : -1.0) * sectionStep_ * (shift ? 10.0 : 1.0);
        p.point = {float(p.point.x + step * n.x), float(p.point.y + step * n.y), float(p.point.z + step * n.z)};
    }
    const double degrees = shift ? 1.0 : 5.0;
    if (key == GLFW_KEY_LEFT || key == GLFW_KEY_RIGHT)  // about the view's up axis
        p.normal = rotated(n, unit(camera().up), key == GLFW_KEY_LEFT ? degrees : -degrees);
    if (key == GLFW_KEY_UP || key == GLFW_KEY_DOWN) {  // about the horizontal axis in the plane
        Float3 axis = unit(cross(n, camera().up));
        if (!(length(axis) > 0.0f)) axis = {1, 0, 0};
        p.normal = rotated(n, axis, key == GLFW_KEY_UP ? degrees : -degrees);
    }
    const int slot = activeSection_;
    if (key == GLFW_KEY_DELETE) {
        scene.setSection(uint32_t(slot), SectionPlane{});
        log_("section " + std::to_string(slot) + ": removed");
        activeSection_ = -1;
        updateOverlay();
        refreshStatus();
        return;
    }
    setSection(scene, uint32_t(slot), p);
    log_(sectionLine(desc));
}

std::string WallInput::sectionLine(const SceneDesc& scene) const {
    if (activeSection_ < 0) return "";
    const SectionPlane& p = scene.sections[activeSection_];
    const std::array<double, 3>& o = scene.origin;
    const Float3 n = unit(p.normal);
    char line[256];
    std::snprintf(line, sizeof line, "section %d: %s, point (%.4f, %.4f, %.4f), normal (%.3f, %.3f, %.3f)", activeSection_,
                  p.enabled ? "on" : "off", o[0] + double(p.point.x), o[1] + double(p.point.y), o[2] + double(p.point.z),
                  double(n.x), double(n.y), double(n.z));
    return line;
}

// One poll's input. A new key binding goes here.
bool WallInput::apply(LiveScene& scene, const InputState& in, double dt) {
    // Esc leaves measure mode first; the wall closes on the next press, not while that one is held.
    for (int key : in.keysPressed)
        if (key == GLFW_KEY_ESCAPE && measuring_) {
            setMeasuring(false);
            escapeHeld_ = true;
        }
    if (escapeHeld_ && !in.keyDown[GLFW_KEY_ESCAPE]) escapeHeld_ = false;
    if (in.closeRequested || (in.keyDown[GLFW_KEY_ESCAPE] && !escapeHeld_)) return false;
    for (int key : in.keysPressed) {
        if (key == GLFW_KEY_M) setMeasuring(!measuring_);
        if (key == GLFW_KEY_H) {
            showStatus_ = !showStatus_;
            statusImage_ = {};
            updateOverlay();
            refreshStatus();
        }
        if (key == GLFW_KEY_T) present_.falseColour = !present_.falseColour;
        if (key == GLFW_KEY_J) ++warpDebugPresses_;  // the re-projection's debug colours (the session toggles them)
        // ] makes the world larger (fewer scene units per metre), [ smaller; two presses double.
        if (options_.interactive && (key == GLFW_KEY_LEFT_BRACKET || key == GLFW_KEY_RIGHT_BRACKET)) {
            setNavigationScale(scale_ * (key == GLFW_KEY_LEFT_BRACKET ? kScaleStep : 1.0 / kScaleStep));
            scene.setCamera(camera());
        }
        if (key == GLFW_KEY_X || key == GLFW_KEY_I || key == GLFW_KEY_G || key == GLFW_KEY_U) partKey(scene, key);
    }
    for (size_t i = 0; i < in.keysPressed.size(); ++i)
        sectionKey(scene, in.keysPressed[i], i < in.modsPressed.size() ? in.modsPressed[i] : 0);
    const bool wasRecording = nav_->recording();
    const bool moved = options_.interactive && nav_->update(in, dt);
    if (wasRecording && !nav_->recording()) {
        std::vector<CameraKey> keys;
        for (const ViewPose& p : nav_->recorded()) keys.push_back({int(keys.size()), cameraOf(base_, p)});
        const auto file = options_.outDir / ("camera_path_" + std::to_string(++recordings_) + ".toml");
        std::filesystem::create_directories(options_.outDir);
        std::ofstream(file) << writeCameraPath(keys, scene.desc().origin);
        log_("recorded " + std::to_string(keys.size()) + " cameras to " + file.string() + " (replay: rtwall run --camera-path " +
             file.string() + ")");
    }
    if (moved) scene.setCamera(camera());

    // Ctrl+click picks the object under the cursor; dragging moves it parallel to the screen.
    // While measuring the same click sets a point and moves nothing (a plain drag navigates, so
    // a plain click would spend a point on every turn of the view).
    const bool ctrl = in.clickMods & GLFW_MOD_CONTROL;
    if (measuring_) {
        if (in.leftPressed && ctrl) measurePick(scene, in.wallX, in.wallY);
        return true;
    }
    if (options_.interactive && in.leftPressed && ctrl) {
        grabbed_ = pick(scene, in.wallX, in.wallY);
        if (grabbed_) {
            grabbedStart_ = scene.desc().instances[grabbed_->instance].transform;
            const Camera cam(camera(), wall_.width, wall_.height);
            char line[128];
            std::snprintf(line, sizeof line, "picked instance %u at distance %.2f", grabbed_->instance,
                          double(grabbed_->t * length(cam.direction(float(in.wallX), float(in.wallY)))));
            // Assemblies name the part, so a reviewer can say which one is meant.
            const InstanceDesc& picked = scene.desc().instances[grabbed_->instance];
            const std::string part = scene.desc().partPath(picked.part);
            // X, I and G act on it: the part, or the mesh of an instance that has none.
            selected_ = part.empty() ? scene.desc().meshes[picked.mesh].name : part;
            log_(part.empty() ? std::string(line) + ", mesh '" + selected_ + "' (X hide, I isolate, G highlight)"
                              : std::string(line) + ", part '" + part + "' (X hide, I isolate, G highlight)");
        }
    }
    if (grabbed_ && in.leftDown && ctrl) {
        const Camera cam(camera(), wall_.width, wall_.height);
        const Float3 o = cam.origin(), d = cam.direction(float(in.wallX), float(in.wallY));
        const Float3 p{o.x + d.x * grabbed_->t, o.y + d.y * grabbed_->t, o.z + d.z * grabbed_->t};
        scene.setInstanceTransform(grabbed_->instance, Transform::translate(double(p.x) - grabbed_->point.x,
                                                                            double(p.y) - grabbed_->point.y,
                                                                            double(p.z) - grabbed_->point.z) *
                                                           grabbedStart_);
    } else if (grabbed_ && !in.leftDown) {
        grabbed_.reset();
    }
    return true;
}

void WallInput::show(const WallFrame& frame, const FrameReport& report, double frameSeconds) {
    if (gl_) {
        gl_->present(frame, present_);
        statusClock_ += frameSeconds;
        if ((measuring_ || activeSection_ >= 0 || !partsLine_.empty()) && !showStatus_ && statusClock_ >= 0.5) {
            // Measure mode, an active section plane or parts hidden alone: their lines are the
            // overlay and the title, and the log has had them.
            statusClock_ = 0;
            std::string text = overlayText_;
            if (!partsLine_.empty()) text += (text.empty() ? "" : "\n") + partsLine_;
            gl_->setStatus(text);
            statusImage_ = textImage(text, 2);
        } else if (showStatus_ && statusClock_ >= 0.5) {
            statusClock_ = 0;
            char line[256];
            std::snprintf(line, sizeof line, "rtwall %.1f fps | %.2f MB/frame %s | late swaps %llu",
                          frameSeconds > 0 ? 1.0 / frameSeconds : 0.0, double(report.bytes) * 1e-6, options_.codec.c_str(),
                          (unsigned long long)gl_->stats().late);
            std::string status = line, overlay = line;
            if (wallHasViews(wall_)) {
                std::snprintf(line, sizeof line, " | scale %.4g units/m", scale_);
                status += line;
                overlay += line;
            }
            for (const ClientReport& c : report.clients) {
                std::snprintf(line, sizeof line, " | client %u: %llu tiles (%.2f MB/s) %.0f%% busy", c.id, (unsigned long long)c.tiles,
                              report.seconds > 0 ? double(c.bytes) / report.seconds * 1e-6 : 0.0, 100.0 * c.busyFraction);
                status += line;
                overlay += "\n" + std::string(line + 3);
            }
            // What the master dropped, refused or lost so far (an operator must see it).
            const std::string counters = "master: " + describeCounters(report.counters);
            status += " | " + counters;
            overlay += "\n" + counters;
            if (!trackerLine_.empty()) {
                status += " | " + trackerLine_;
                overlay += "\n" + trackerLine_;
            }
            if (!overlayText_.empty()) {
                status += " | " + overlayText_;
                overlay += "\n" + overlayText_;
            }
            if (!partsLine_.empty()) {
                status += " | " + partsLine_;
                overlay += "\n" + partsLine_;
            }
            gl_->setStatus(status);
            statusImage_ = textImage(overlay, 2);  // shown from the next frame on
            log_(status);
        }
    } else if (headless_) {
        headless_->present(frame, present_);
    }
}

void WallInput::showConsole(const std::string& lines, const FrameReport& report, double frameSeconds) {
    if (!gl_) return;
    std::string text = lines;
    if (showStatus_) {
        char line[160];
        std::snprintf(line, sizeof line, "\nrtwall %.1f fps | %.2f MB/frame to the nodes %s\nmaster: ", frameSeconds > 0 ? 1.0 / frameSeconds : 0.0,
                      double(report.bytes) * 1e-6, options_.codec.c_str());
        text += line + describeCounters(report.counters);
    }
    if (!overlayText_.empty()) text += "\n" + overlayText_;
    if (!partsLine_.empty()) text += "\n" + partsLine_;
    WallFrame frame;
    frame.number = report.frame;
    frame.left.width = console_.width;
    frame.left.height = console_.height;
    frame.left.rgb.assign(size_t(console_.width) * size_t(console_.height) * 3, 0);
    const Image t = textImage(text, 1);
    for (int y = 0; y < std::min(t.height, frame.left.height - 8); ++y)
        for (int x = 0; x < std::min(t.width, frame.left.width - 8); ++x)
            for (int c = 0; c < 3; ++c)
                frame.left.rgb[(size_t(y + 8) * size_t(frame.left.width) + size_t(x + 8)) * 3 + size_t(c)] =
                    t.rgb[(size_t(y) * size_t(t.width) + size_t(x)) * 3 + size_t(c)];
    gl_->setStatus(lines.substr(0, lines.find('\n')));
    gl_->present(frame);
}

}  // namespace rtwall::wall
