// WebApi: the operator console's routes (docs/web-console.md, "API"). Every request is checked
// here, before anything is read or changed: the token, the route, the JSON body, each number
// (finite, within 1e15), each id. A bad request is a 4xx with one line {"error": "..."}; what it
// asked changes nothing. Changes run on the session's thread through the backend.
#include <rtwall/web.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <future>
#include <random>
#include <thread>

namespace rtwall {

using nlohmann::json;

namespace {

// JSON text; bytes that are not UTF-8 (a part's name from a file, a path asked for) become U+FFFD.
std::string text(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }

WebResponse error(int status, const std::string& why) {
    WebResponse r;
    r.status = status;
    r.body = text(json{{"error", why}});
    return r;
}

WebResponse ok(const json& j) {
    WebResponse r;
    r.body = text(j);
    return r;
}

// A request's problem: answered with its status and reason.
struct Refusal {
    int status;
    std::string why;
};

json parseBody(const WebRequest& q) {
    if (q.body.empty()) throw Refusal{400, "the body must be a JSON object"};
    json j = json::parse(q.body, nullptr, false, true);
    if (j.is_discarded()) throw Refusal{400, "the body is not valid JSON"};
    if (!j.is_object()) throw Refusal{400, "the body must be a JSON object"};
    return j;
}

// Only the keys named may be given: a typo is an error, not a silent default.
void onlyKeys(const json& j, std::initializer_list<const char*> keys) {
    for (auto it = j.begin(); it != j.end(); ++it) {
        bool known = false;
        for (const char* k : keys) known = known || it.key() == k;
        if (!known) {
            std::string list;
            for (const char* k : keys) list += std::string(list.empty() ? "" : ", ") + k;
            throw Refusal{400, "unknown key '" + it.key() + "' (known: " + list + ")"};
        }
    }
}

double number(const json& j, const char* key, double lo = -1e15, double hi = 1e15) {
    const json& v = j.at(key);
    if (!v.is_number()) throw Refusal{400, std::string("'") + key + "' must be a number"};
    const double d = v.get<double>();
    if (!std::isfinite(d) || d < lo || d > hi)
        throw Refusal{400, std::string("'") + key + "' must be a finite number within [" + json(lo).dump() + ", " + json(hi).dump() + "]"};
    return d;
}

std::array<double, 3> vec3(const json& j, const char* key) {
    const json& v = j.at(key);
    if (!v.is_array() || v.size() != 3) throw Refusal{400, std::string("'") + key + "' must be an array of 3 numbers"};
    std::array<double, 3> out{};
    for (size_t i = 0; i < 3; ++i) {
        if (!v[i].is_number()) throw Refusal{400, std::string("'") + key + "' must be an array of 3 numbers"};
        out[i] = v[i].get<double>();
        if (!std::isfinite(out[i]) || std::fabs(out[i]) > 1e15)
            throw Refusal{400, std::string("'") + key + "' must hold finite numbers within 1e15"};
    }
    return out;
}

bool boolean(const json& j, const char* key) {
    const json& v = j.at(key);
    if (!v.is_boolean()) throw Refusal{400, std::string("'") + key + "' must be true or false"};
    return v.get<bool>();
}

std::string text(const json& j, const char* key, size_t maxLength) {
    const json& v = j.at(key);
    if (!v.is_string()) throw Refusal{400, std::string("'") + key + "' must be a string"};
    const std::string s = v.get<std::string>();
    if (s.empty() || s.size() > maxLength)
        throw Refusal{400, std::string("'") + key + "' must be 1 to " + std::to_string(maxLength) + " bytes"};
    for (unsigned char ch : s)
        if (ch < 0x20 || ch == 0x7f) throw Refusal{400, std::string("'") + key + "' must not hold control characters"};
    return s;
}

double norm(const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// A decimal id from a path segment: digits only, below `count`.
size_t idOf(const std::string& segment, size_t count, const char* what) {
    if (segment.empty() || segment.size() > 9 || segment.find_first_not_of("0123456789") != std::string::npos)
        throw Refusal{404, std::string("no ") + what + " '" + segment.substr(0, 40) + "'"};
    const size_t id = std::stoul(segment);
    if (id >= count) throw Refusal{404, std::string("no ") + what + " " + segment};
    return id;
}

json world(Float3 p, const std::array<double, 3>& o) { return {double(p.x) + o[0], double(p.y) + o[1], double(p.z) + o[2]}; }
Float3 relative(const std::array<double, 3>& p, const std::array<double, 3>& o) {
    return {float(p[0] - o[0]), float(p[1] - o[1]), float(p[2] - o[2])};
}

json cameraJson(const CameraDesc& c, const std::array<double, 3>& o) {
    return {{"position", world(c.position, o)}, {"target", world(c.lookAt, o)}, {"up", {c.up.x, c.up.y, c.up.z}}, {"fov", c.fovY}};
}

// The plane n.p = d in the file's coordinates: n unit, d its offset along n.
json sectionJson(size_t id, const SectionPlane& p, const std::array<double, 3>& o) {
    const double n = std::sqrt(double(p.normal.x) * p.normal.x + double(p.normal.y) * p.normal.y + double(p.normal.z) * p.normal.z);
    const std::array<double, 3> u{p.normal.x / n, p.normal.y / n, p.normal.z / n};
    const double d = u[0] * (double(p.point.x) + o[0]) + u[1] * (double(p.point.y) + o[1]) + u[2] * (double(p.point.z) + o[2]);
    return {{"id", id}, {"normal", u}, {"offset", d}, {"enabled", p.enabled}, {"caps", p.caps}};
}

SectionPlane planeOf(const std::array<double, 3>& normal, double offset, const std::array<double, 3>& o, SectionPlane p) {
    const double n = norm(normal);
    if (!(n > 1e-12)) throw Refusal{400, "'normal' must not be zero"};
    const std::array<double, 3> u{normal[0] / n, normal[1] / n, normal[2] / n};
    p.normal = {float(u[0]), float(u[1]), float(u[2])};
    p.point = relative({u[0] * offset, u[1] * offset, u[2] * offset}, o);
    p.enabled = true;
    return p;
}

bool used(const SectionPlane& p) { return p.enabled || !(p == SectionPlane{}); }

json measurementJson(size_t id, const Measurement& m) {
    json j{{"id", id}, {"a", m.a}, {"distance", m.distance}};
    if (m.b) j["b"] = *m.b;
    return j;
}

// A part's state from its instances' visibilities.
json partJson(size_t id, const ConsolePart& p, const std::vector<Visibility>& vis) {
    size_t hidden = 0, highlighted = 0;
    for (uint32_t i : p.instances) {
        const Visibility v = i < vis.size() ? vis[i] : Visibility::Shown;
        hidden += v == Visibility::Hidden;
        highlighted += v == Visibility::Highlighted;
    }
    return {{"id", id},
            {"name", p.name},
            {"path", p.path},
            {"parent", p.parent},
            {"instances", p.instances.size()},
            {"visible", hidden < p.instances.size() || p.instances.empty()},
            {"hidden", hidden},
            {"highlighted", highlighted}};
}

std::vector<std::string> split(const std::string& path) {
    std::vector<std::string> out;
    size_t i = 1;
    while (i <= path.size()) {
        const size_t j = path.find('/', i);
        out.push_back(path.substr(i, j == std::string::npos ? std::string::npos : j - i));
        if (j == std::string::npos) break;
        i = j + 1;
    }
    return out;
}

}  // namespace

std::vector<ConsolePart> consoleParts(const SceneDesc& scene) {
    std::vector<ConsolePart> out;
    if (!scene.parts.empty()) {
        out.resize(scene.parts.size());
        for (size_t i = 0; i < scene.parts.size(); ++i) {
            out[i].name = scene.parts[i].name;
            out[i].path = scene.partPath(int32_t(i));
            out[i].parent = scene.parts[i].parent;
        }
        for (size_t i = 0; i < scene.instances.size(); ++i)
            for (int32_t p = scene.instances[i].part; p >= 0 && size_t(p) < out.size(); p = scene.parts[size_t(p)].parent)
                out[size_t(p)].instances.push_back(uint32_t(i));
    }
    // Instances without a part go by their mesh's name, as the part view matches them.
    std::map<std::string, size_t> byMesh;
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        if (scene.instances[i].part >= 0) continue;
        const std::string& name = scene.meshes[scene.instances[i].mesh].name;
        if (name.empty()) continue;  // nothing a pattern could name
        auto [it, added] = byMesh.emplace(name, out.size());
        if (added) out.push_back({name, name, -1, {}});
        out[it->second].instances.push_back(uint32_t(i));
    }
    return out;
}

std::string makeWebToken() {
    static constexpr char kChars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
    std::random_device rd;
    std::string t;
    for (int i = 0; i < 32; ++i) t += kChars[rd() % 62];
    return t;
}

WebApi::WebApi(ConsoleBackend& backend, std::string token, std::chrono::milliseconds commandTimeout,
               std::chrono::milliseconds screenshotInterval)
    : backend_(backend), token_(std::move(token)), timeout_(commandTimeout), shotInterval_(screenshotInterval) {
    if (token_.size() < 16) throw std::invalid_argument("WebApi: a token of at least 16 characters");
}

namespace {
bool sameSecret(const std::string& given, const std::string& token) {
    // Constant time in the token: every byte is looked at whatever the given one holds.
    unsigned diff = given.size() != token.size();
    for (size_t i = 0; i < token.size(); ++i) diff |= unsigned(uint8_t(token[i]) ^ uint8_t(i < given.size() ? given[i] : 0));
    return diff == 0;
}
}  // namespace

bool WebApi::authorized(const WebRequest& q) const {
    if (q.authorization.starts_with("Bearer ") && sameSecret(q.authorization.substr(7), token_)) return true;
    // Cookie: "a=b; rtwall_token=T; c=d"
    size_t at = 0;
    while (at < q.cookie.size()) {
        size_t end = q.cookie.find(';', at);
        if (end == std::string::npos) end = q.cookie.size();
        std::string item = q.cookie.substr(at, end - at);
        while (!item.empty() && item.front() == ' ') item.erase(0, 1);
        if (item.starts_with("rtwall_token=") && sameSecret(item.substr(13), token_)) return true;
        at = end + 1;
    }
    return false;
}

WebResponse WebApi::handle(const WebRequest& q) {
    // The printed URL: its token sets the cookie the page's requests carry, then the page without it.
    if (q.method == "GET" && (q.path == "/" || q.path == "/index.html") && q.params.count("token")) {
        if (!sameSecret(q.params.at("token"), token_)) return error(401, "wrong token");
        WebResponse r;
        r.status = 303;
        r.contentType = "text/plain";
        r.headers = {{"Location", "/"}, {"Set-Cookie", "rtwall_token=" + token_ + "; Path=/; HttpOnly; SameSite=Strict"}};
        return r;
    }
    if (!authorized(q))
        return error(401, "a token is needed: 'Authorization: Bearer TOKEN', or open the URL rtwall run printed once");
    try {
        if (!q.path.starts_with("/api/")) {
            if (q.method != "GET") throw Refusal{405, q.method + " " + q.path + ": the page's files are read only"};
            const SiteFile* f = siteFile(q.path == "/" ? "/index.html" : q.path);
            if (!f) throw Refusal{404, "no such file: " + q.path.substr(0, 100)};
            WebResponse r;
            r.contentType = f->type;
            r.body = std::string(f->body);
            r.headers = {{"Cache-Control", "no-cache"}};
            return r;
        }
        const std::vector<std::string> seg = split(q.path.substr(4));  // "/api/parts/3" -> {"parts", "3"}
        const std::string& what = seg.empty() ? std::string() : seg[0];
        const std::shared_ptr<const ConsoleSnapshot> snap = backend_.snapshot();
        const std::array<double, 3>& o = snap->origin;
        auto route = [&](const char* method, const char* name, size_t segments) {
            return q.method == method && what == name && seg.size() == segments;
        };
        // Runs a change on the session's thread and waits for its answer.
        auto change = [&](std::function<WebResponse(WallSession&)> f) {
            auto answer = std::make_shared<std::promise<WebResponse>>();
            std::future<WebResponse> got = answer->get_future();
            const bool ran = backend_.run(
                [answer, f = std::move(f)](WallSession& s) {
                    try {
                        answer->set_value(f(s));
                    } catch (const Refusal& r) {
                        answer->set_value(error(r.status, r.why));
                    } catch (const std::exception& e) {
                        answer->set_value(error(422, e.what()));
                    }
                },
                timeout_);
            if (!ran || got.wait_for(std::chrono::milliseconds(0)) != std::future_status::ready)
                return error(503, "the wall did not take the change within " + std::to_string(timeout_.count()) + " ms (it may still apply it)");
            return got.get();
        };

        if (route("GET", "status", 1)) {
            const ConsoleSnapshot& s = *snap;
            json clients = json::array();
            for (const auto& c : s.clients)
                clients.push_back({{"id", c.id}, {"tiles", c.tiles}, {"busy", c.busy}, {"megabytes", c.megabytes}});
            return ok({{"frame", s.frame},
                       {"steps", s.steps},
                       {"fps", s.fps},
                       {"frame_ms", s.frameMs},
                       {"link_mb_s", s.linkMegabytesPerSecond},
                       {"tile_latency_ms", s.tileLatencyMs},
                       {"affinity", s.affinity},
                       {"tiles_stolen", s.tilesStolen},
                       {"clients", clients},
                       {"tracker", s.tracker},
                       {"operating_point", s.operatingPoint},
                       {"wall", {{"width", s.wallWidth}, {"height", s.wallHeight}, {"stereo", s.stereo}, {"on_nodes", s.onNodes}}},
                       {"camera", cameraJson(s.session.camera, o)},
                       {"flying", s.flying}});
        }
        if (route("GET", "thumbnail.jpg", 1)) {
            uint32_t frame = 0;
            const auto jpeg = backend_.thumbnail(&frame);
            if (!jpeg) throw Refusal{503, "no thumbnail yet: ask again in a moment"};
            WebResponse r;
            r.contentType = "image/jpeg";
            r.body.assign(jpeg->begin(), jpeg->end());
            r.headers = {{"Cache-Control", "no-store"}, {"X-Rtwall-Frame", std::to_string(frame)}};
            return r;
        }
        if (route("GET", "screenshot.png", 1)) {
            int eye = 0;
            if (q.params.count("eye")) {
                const std::string& e = q.params.at("eye");
                if (e == "right") eye = 1;
                else if (e != "left") throw Refusal{400, "'eye' must be left or right"};
                if (eye == 1 && !snap->stereo) throw Refusal{400, "the wall is not stereo: it has no right eye"};
            }
            if (shooting_.exchange(true)) throw Refusal{429, "a screenshot is being made: one at a time"};
            struct Done {
                std::atomic<bool>& flag;
                ~Done() { flag = false; }
            } done{shooting_};
            // At most two a second: a quick second one waits for its turn (on this thread, never the wall's).
            const auto last = std::chrono::steady_clock::time_point(std::chrono::steady_clock::duration(lastShot_.load()));
            if (shotInterval_.count() > 0) std::this_thread::sleep_until(last + shotInterval_);
            lastShot_ = std::chrono::steady_clock::now().time_since_epoch().count();
            std::string why;
            const std::optional<Image> img = backend_.screenshot(eye, timeout_, &why);
            if (!img) throw Refusal{503, why.empty() ? "no frame to take yet" : why};
            WebResponse r;
            r.contentType = "image/png";
            const std::vector<uint8_t> png = encodePng(*img);
            r.body.assign(png.begin(), png.end());
            r.headers = {{"Cache-Control", "no-store"},
                         {"Content-Disposition", "attachment; filename=\"wall_" + std::to_string(snap->frame) + ".png\""}};
            return r;
        }
        if (what == "parts") {
            const std::vector<ConsolePart>& parts = backend_.parts();
            if (route("GET", "parts", 1)) {
                json list = json::array();
                for (size_t i = 0; i < parts.size(); ++i) list.push_back(partJson(i, parts[i], *snap->visibility));
                const PartView& v = snap->session.parts;
                return ok({{"parts", list}, {"view", {{"hide", v.hide}, {"isolate", v.isolate}, {"highlight", v.highlight}}}});
            }
            if (route("POST", "parts", 1)) {  // {"show_all": true}
                const json j = parseBody(q);
                onlyKeys(j, {"show_all"});
                if (!j.contains("show_all") || !boolean(j, "show_all")) throw Refusal{400, "give {\"show_all\": true}"};
                return change([](WallSession& s) {
                    s.showAllParts();
                    return ok({{"shown", true}});
                });
            }
            if (route("POST", "parts", 2)) {
                const size_t id = idOf(seg[1], parts.size(), "part");
                const json j = parseBody(q);
                onlyKeys(j, {"visible", "highlight", "isolate"});
                if (j.empty()) throw Refusal{400, "give 'visible', 'highlight' or 'isolate'"};
                std::optional<bool> visible, highlight, isolate;
                if (j.contains("visible")) visible = boolean(j, "visible");
                if (j.contains("highlight")) highlight = boolean(j, "highlight");
                if (j.contains("isolate")) isolate = boolean(j, "isolate");
                const std::string path = parts[id].path;
                ConsoleBackend* backend = &backend_;
                return change([=](WallSession& s) {
                    // As the keys X, G and I do: the part view's patterns, the part's path in them.
                    PartView v = s.partView();
                    auto drop = [&](std::vector<std::string>& list) { list.erase(std::remove(list.begin(), list.end(), path), list.end()); };
                    if (visible) {
                        drop(v.hide);
                        if (!*visible) {
                            v.hide.push_back(path);
                            drop(v.highlight);
                        }
                    }
                    if (highlight) {
                        drop(v.highlight);
                        if (*highlight) v.highlight.push_back(path);
                    }
                    if (isolate) {
                        if (*isolate) v.isolate = {path};
                        else drop(v.isolate);
                    }
                    s.setPartView(v);
                    std::vector<Visibility> vis;
                    for (const InstanceDesc& in : s.scene().instances) vis.push_back(in.visibility);
                    return ok(partJson(id, backend->parts()[id], vis));
                });
            }
        }
        if (what == "sections") {
            const SectionPlanes& planes = snap->session.sections;
            if (route("GET", "sections", 1)) {
                json list = json::array();
                for (size_t i = 0; i < planes.size(); ++i)
                    if (used(planes[i])) list.push_back(sectionJson(i, planes[i], o));
                return ok({{"sections", list}, {"slots", kMaxSections}});
            }
            if (route("POST", "sections", 1)) {  // {"normal": [x, y, z], "offset": d}
                const json j = parseBody(q);
                onlyKeys(j, {"normal", "offset", "caps"});
                if (!j.contains("normal") || !j.contains("offset")) throw Refusal{400, "give 'normal' and 'offset' (the plane n.p = offset)"};
                SectionPlane p;
                if (j.contains("caps")) p.caps = boolean(j, "caps");
                p = planeOf(vec3(j, "normal"), number(j, "offset"), o, p);
                return change([p](WallSession& s) {
                    const SectionPlanes& now = s.scene().sections;
                    for (size_t i = 0; i < now.size(); ++i)
                        if (!used(now[i])) {
                            s.setSection(uint32_t(i), p);
                            return ok(sectionJson(i, p, s.scene().origin));
                        }
                    throw Refusal{409, "all " + std::to_string(kMaxSections) + " section planes are in use: remove one first"};
                });
            }
            if ((q.method == "POST" || q.method == "DELETE") && seg.size() == 2) {
                const size_t id = idOf(seg[1], planes.size(), "section plane");
                if (!used(planes[id])) throw Refusal{404, "no section plane " + seg[1]};
                if (q.method == "DELETE")
                    return change([id](WallSession& s) {
                        s.setSection(uint32_t(id), SectionPlane{});
                        return ok({{"removed", id}});
                    });
                // Move ({"offset": d}, {"normal": [..]}), flip ({"flip": true}), switch off and on ({"enabled": b}).
                const json j = parseBody(q);
                onlyKeys(j, {"normal", "offset", "flip", "enabled", "caps"});
                std::optional<std::array<double, 3>> normal;
                std::optional<double> offset;
                if (j.contains("normal")) normal = vec3(j, "normal");
                if (j.contains("offset")) offset = number(j, "offset");
                const bool flip = j.contains("flip") && boolean(j, "flip");
                std::optional<bool> enabled, caps;
                if (j.contains("enabled")) enabled = boolean(j, "enabled");
                if (j.contains("caps")) caps = boolean(j, "caps");
                if (normal && !(norm(*normal) > 1e-12)) throw Refusal{400, "'normal' must not be zero"};
                return change([=](WallSession& s) {
                    const std::array<double, 3>& origin = s.scene().origin;
                    SectionPlane p = s.scene().sections[id];
                    if (!used(p)) throw Refusal{404, "no section plane " + std::to_string(id)};
                    const json now = sectionJson(id, p, origin);
                    std::array<double, 3> n = normal ? *normal : now["normal"].get<std::array<double, 3>>();
                    double d = offset ? *offset : now["offset"].get<double>();
                    if (normal && !offset) {  // a new normal alone turns the plane about its point (the one nearest the origin)
                        const double len = norm(n);
                        d = (n[0] * (p.point.x + origin[0]) + n[1] * (p.point.y + origin[1]) + n[2] * (p.point.z + origin[2])) / len;
                    }
                    if (flip) {
                        n = {-n[0], -n[1], -n[2]};
                        d = -d;
                    }
                    const bool on = enabled.value_or(p.enabled);
                    if (caps) p.caps = *caps;
                    p = planeOf(n, d, origin, p);
                    p.enabled = on;
                    s.setSection(uint32_t(id), p);
                    return ok(sectionJson(id, p, origin));
                });
            }
        }
        if (what == "bookmarks") {
            const std::vector<Bookmark>& marks = snap->session.bookmarks;
            if (route("GET", "bookmarks", 1)) {
                json list = json::array();
                for (size_t i = 0; i < marks.size(); ++i)
                    list.push_back({{"id", i}, {"name", marks[i].name}, {"camera", cameraJson(marks[i].camera, o)}});
                return ok({{"bookmarks", list}});
            }
            if (route("POST", "bookmarks", 1)) {  // {"name": "..."}: the current view
                const json j = parseBody(q);
                onlyKeys(j, {"name"});
                if (!j.contains("name")) throw Refusal{400, "give 'name'"};
                const std::string name = text(j, "name", 200);
                return change([name](WallSession& s) {
                    s.saveBookmark(name);
                    for (size_t i = 0; i < s.bookmarks().size(); ++i)
                        if (s.bookmarks()[i].name == name)
                            return ok({{"id", i}, {"name", name}, {"camera", cameraJson(s.bookmarks()[i].camera, s.scene().origin)}});
                    throw Refusal{500, "the bookmark was not kept"};
                });
            }
            if ((q.method == "DELETE" && seg.size() == 2) || (q.method == "POST" && seg.size() == 3 && seg[2] == "go")) {
                const size_t id = idOf(seg[1], marks.size(), "bookmark");
                const std::string name = marks[id].name;
                double seconds = 0.8;
                if (q.method == "POST" && !q.body.empty()) {
                    const json j = parseBody(q);
                    onlyKeys(j, {"seconds"});
                    if (j.contains("seconds")) seconds = number(j, "seconds", 0, 60);
                }
                const bool go = q.method == "POST";
                return change([=](WallSession& s) {
                    if (go) {
                        if (!s.goToBookmark(name, seconds)) throw Refusal{409, "the camera follows a camera path: it cannot go to a bookmark"};
                        return ok({{"going", name}, {"seconds", seconds}});
                    }
                    if (!s.deleteBookmark(name)) throw Refusal{404, "no bookmark '" + name + "'"};
                    return ok({{"deleted", name}});
                });
            }
        }
        if (what == "camera") {
            if (route("GET", "camera", 1)) return ok(cameraJson(snap->session.camera, o));
            if (route("POST", "camera", 1)) {  // {"position": [..], "target": [..], "up": [..]}
                const json j = parseBody(q);
                onlyKeys(j, {"position", "target", "up", "fov", "seconds"});
                if (!j.contains("position") || !j.contains("target")) throw Refusal{400, "give 'position' and 'target'"};
                CameraDesc c = snap->session.camera;
                const std::array<double, 3> pos = vec3(j, "position"), target = vec3(j, "target");
                if (pos == target) throw Refusal{400, "'position' and 'target' must differ"};
                c.position = relative(pos, o);
                c.lookAt = relative(target, o);
                if (j.contains("up")) {
                    const std::array<double, 3> up = vec3(j, "up");
                    if (!(norm(up) > 1e-12)) throw Refusal{400, "'up' must not be zero"};
                    c.up = {float(up[0]), float(up[1]), float(up[2])};
                }
                if (j.contains("fov")) c.fovY = float(number(j, "fov", 0.01, 179));
                const double seconds = j.contains("seconds") ? number(j, "seconds", 0, 60) : 0.0;
                return change([c, seconds](WallSession& s) {
                    if (!s.flyTo(c, seconds)) throw Refusal{409, "the camera follows a camera path"};
                    return ok({{"camera", cameraJson(c, s.scene().origin)}, {"seconds", seconds}});
                });
            }
        }
        if (what == "measurements") {
            const std::vector<Measurement>& ms = snap->session.measurements;
            if (route("GET", "measurements", 1)) {
                json list = json::array();
                for (size_t i = 0; i < ms.size(); ++i) list.push_back(measurementJson(i, ms[i]));
                return ok({{"measurements", list}});
            }
            if (route("POST", "measurements", 1)) {  // {"a": [x, y], "b": [x, y]}: wall pixels
                const json j = parseBody(q);
                onlyKeys(j, {"a", "b"});
                std::array<double, 4> px{};
                for (int k = 0; k < 2; ++k) {
                    const char* key = k ? "b" : "a";
                    if (!j.contains(key) || !j[key].is_array() || j[key].size() != 2 || !j[key][0].is_number() || !j[key][1].is_number())
                        throw Refusal{400, std::string("'") + key + "' must be [x, y], a wall pixel"};
                    px[size_t(2 * k)] = j[key][0].get<double>();
                    px[size_t(2 * k + 1)] = j[key][1].get<double>();
                    if (!(px[size_t(2 * k)] >= 0 && px[size_t(2 * k)] < snap->wallWidth && px[size_t(2 * k + 1)] >= 0 &&
                          px[size_t(2 * k + 1)] < snap->wallHeight))
                        throw Refusal{400, std::string("'") + key + "' must lie on the wall (0 <= x < " + std::to_string(snap->wallWidth) +
                                               ", 0 <= y < " + std::to_string(snap->wallHeight) + ")"};
                }
                return change([px](WallSession& s) {
                    const std::optional<Measurement> m = s.measureBetween(px[0], px[1], px[2], px[3]);
                    if (!m) throw Refusal{422, "nothing of the scene under one of the points"};
                    return ok(measurementJson(s.measurements().size() - 1, *m));
                });
            }
            if (q.method == "DELETE" && seg.size() == 2) {
                const size_t id = idOf(seg[1], ms.size(), "measurement");
                const Measurement m = ms[id];
                return change([id, m](WallSession& s) {
                    if (id >= s.measurements().size() || !(s.measurements()[id] == m)) throw Refusal{409, "the measurements changed: list them again"};
                    s.deleteMeasurement(id);
                    return ok({{"deleted", id}});
                });
            }
        }
        if (what == "session" && seg.size() == 1) {
            if (q.method == "GET") {
                const SceneDesc* scene = backend_.scene();
                if (!scene) throw Refusal{503, "no scene"};
                WebResponse r;
                r.contentType = "application/toml";
                r.body = writeSessionState(snap->session, *scene);
                r.headers = {{"Content-Disposition", "attachment; filename=\"session.toml\""}};
                return r;
            }
            if (q.method == "POST") {  // a session file's text
                const SceneDesc* scene = backend_.scene();
                if (!scene) throw Refusal{503, "no scene"};
                SessionState st;
                try {
                    st = parseSessionState(q.body, "session", *scene);
                } catch (const InputError& e) {
                    throw Refusal{400, e.what()};
                }
                return change([st](WallSession& s) {
                    s.restoreSession(st);
                    return ok({{"restored", true}, {"bookmarks", st.bookmarks.size()}, {"moved", st.moved.size()},
                               {"measurements", st.measurements.size()}});
                });
            }
        }
        const bool known = what == "status" || what == "thumbnail.jpg" || what == "screenshot.png" || what == "parts" ||
                           what == "sections" || what == "bookmarks" || what == "camera" || what == "measurements" ||
                           what == "session" || what == "events";
        if (known) throw Refusal{405, q.method + " " + q.path.substr(0, 100) + ": not a route of the API (docs/web-console.md)"};
        throw Refusal{404, "no such route: " + q.path.substr(0, 100)};
    } catch (const Refusal& r) {
        return error(r.status, r.why);
    } catch (const json::exception& e) {  // a type the checks above did not foresee
        return error(400, std::string("bad JSON value: ") + e.what());
    }
}

}  // namespace rtwall
