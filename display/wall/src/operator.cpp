// The operator's side of WallSession (issue 31): commands posted from other threads (the web
// console's), step observers, bookmarks, smooth camera flights, kept measurements, and the
// session state a session file holds. Everything here runs on the session's thread; post() is
// the one door in from others.
#include "session_impl.h"

#include <cmath>

namespace rtwall {

void WallSession::post(std::function<void(WallSession&)> command) {
    std::lock_guard<std::mutex> lock(impl_->commandsMutex);
    impl_->commands.push_back(std::move(command));
}

void WallSession::addStepObserver(std::function<void(const WallSession&)> observer) {
    impl_->observers.push_back(std::move(observer));
}

void WallSession::Impl::runOperator(WallSession& self) {
    std::vector<std::function<void(WallSession&)>> now;
    {
        std::lock_guard<std::mutex> lock(commandsMutex);
        now.swap(commands);
    }
    for (auto& command : now) {
        try {
            command(self);
        } catch (const std::exception& e) {  // a command answers its caller itself; this is a bug's last word
            log(std::string("console: a command failed: ") + e.what());
        }
    }
    if (!flight) return;
    const double t = std::min(1.0, std::chrono::duration<double>(std::chrono::steady_clock::now() - flight->start).count() /
                                       std::max(1e-9, flight->seconds));
    CameraDesc c = flight->to;
    if (t < 1.0) c = mixCameras(flight->from, flight->to, float(t * t * (3.0 - 2.0 * t)));  // smoothstep: no jolt at either end
    else flight.reset();
    input->setCamera(c);
    live->setCamera(c);
}

void WallSession::Impl::notifyObservers(const WallSession& self) {
    for (auto& o : observers) o(self);
}

const std::vector<Bookmark>& WallSession::bookmarks() const { return impl_->bookmarks; }

void WallSession::saveBookmark(const std::string& name) {
    Impl& s = *impl_;
    const Bookmark b{name, camera()};
    for (Bookmark& e : s.bookmarks)
        if (e.name == name) {
            e = b;
            s.log("bookmark '" + name + "' replaced");
            return;
        }
    s.bookmarks.push_back(b);
    s.log("bookmark '" + name + "' saved");
}

bool WallSession::goToBookmark(const std::string& name, double seconds) {
    for (const Bookmark& b : impl_->bookmarks)
        if (b.name == name) return flyTo(b.camera, seconds);
    return false;
}

bool WallSession::deleteBookmark(const std::string& name) {
    std::vector<Bookmark>& v = impl_->bookmarks;
    const auto it = std::find_if(v.begin(), v.end(), [&](const Bookmark& b) { return b.name == name; });
    if (it == v.end()) return false;
    v.erase(it);
    impl_->log("bookmark '" + name + "' deleted");
    return true;
}

bool WallSession::flyTo(const CameraDesc& target, double seconds) {
    Impl& s = *impl_;
    if (!s.path.empty()) {
        s.log("console: the camera path moves the camera; the view was not changed");
        return false;
    }
    if (s.config.orbit != 0.0 && !s.input->windowed()) {
        s.config.orbit = 0.0;
        s.log("orbit stopped: the operator moved the camera");
    }
    CameraDesc to = camera();  // the viewer's name and projection; the pose given
    to.position = target.position;
    to.lookAt = target.lookAt;
    to.up = target.up;
    to.fovY = target.fovY;
    if (seconds <= 0) {
        s.flight.reset();
        setCamera(to);
        return true;
    }
    s.flight = Impl::Flight{camera(), to, std::chrono::steady_clock::now(), seconds};
    return true;
}

bool WallSession::flying() const { return impl_->flight.has_value(); }

const std::vector<Measurement>& WallSession::measurements() const { return impl_->input->kept(); }

std::optional<Measurement> WallSession::measureBetween(double ax, double ay, double bx, double by) {
    return impl_->input->measureBetween(*impl_->live, ax, ay, bx, by);
}

bool WallSession::deleteMeasurement(size_t index) {
    std::vector<Measurement>& v = impl_->input->kept();
    if (index >= v.size()) return false;
    v.erase(v.begin() + long(index));
    return true;
}

const WallConfig& WallSession::wallConfig() const { return impl_->wallConfig; }
double WallSession::frameSeconds() const { return impl_->frameTimes.empty() ? 0.0 : impl_->frameTimes.back(); }
size_t WallSession::steps() const { return impl_->frameTimes.size(); }
std::string WallSession::operatingPointName() const {
    const OperatingPointController* c = impl_->tuning ? impl_->tuning->controller() : nullptr;
    return c ? c->current().name : std::string();
}

SessionState WallSession::sessionState() const {
    const Impl& s = *impl_;
    SessionState st;
    st.camera = camera();
    st.bookmarks = s.bookmarks;
    st.sections = scene().sections;
    st.parts = partView();
    const std::vector<InstanceDesc>& in = scene().instances;
    for (size_t i = 0; i < in.size() && i < s.loadedTransforms.size(); ++i)
        if (!(in[i].transform == s.loadedTransforms[i])) st.moved.emplace_back(uint32_t(i), in[i].transform);
    st.measurements = s.input->kept();
    return st;
}

void WallSession::restoreSession(const SessionState& state) {
    Impl& s = *impl_;
    const SceneDesc& desc = scene();
    for (const auto& [i, t] : state.moved)
        if (i >= desc.instances.size())
            throw InputError("session: instance " + std::to_string(i) + " does not exist (the scene has " +
                             std::to_string(desc.instances.size()) + ")");
    visibilityOf(desc, state.parts);  // a pattern that names nothing throws before anything changed
    for (const SectionPlane& p : state.sections)
        if (p.enabled && !(std::isfinite(p.normal.x) && std::isfinite(p.normal.y) && std::isfinite(p.normal.z) && length(p.normal) > 0))
            throw InputError("session: a section plane's normal is zero or not finite");
    s.flight.reset();
    if (s.config.orbit != 0.0 && !s.input->windowed()) s.config.orbit = 0.0;  // the session's camera stays
    setCamera(state.camera);
    s.bookmarks = state.bookmarks;
    for (int i = 0; i < kMaxSections; ++i)
        if (!(desc.sections[size_t(i)] == state.sections[size_t(i)])) setSection(uint32_t(i), state.sections[size_t(i)]);
    setPartView(state.parts);
    std::vector<Transform> want = s.loadedTransforms;
    for (const auto& [i, t] : state.moved) want[i] = t;
    for (size_t i = 0; i < want.size(); ++i)
        if (!(desc.instances[i].transform == want[i])) setInstanceTransform(uint32_t(i), want[i]);
    s.input->kept() = state.measurements;
    s.log(format("session restored: %zu bookmarks, %zu moved instances, %zu measurements", state.bookmarks.size(),
                 state.moved.size(), state.measurements.size()));
}

}  // namespace rtwall
