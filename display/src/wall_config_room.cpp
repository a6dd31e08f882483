// The wall config's sections about how the room meets the scene: [tracking] (where the head and
// the flystick come from and how the tracker's room lies in the wall's) and [navigation] (how
// the wall's metres lie in the scene). Split from wall_config.cpp, which reads the screens.
#include "wall_config_sections.h"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace rtwall {

namespace {

// "dtrack://A.B.C.D:PORT": the IPv4 address to listen on and the UDP port.
bool parseSource(const std::string& s, std::string& address, int& port) {
    const std::string scheme = "dtrack://";
    if (s.rfind(scheme, 0) != 0) return false;
    const std::string rest = s.substr(scheme.size());
    const size_t colon = rest.rfind(':');
    if (colon == std::string::npos) return false;
    const std::string a = rest.substr(0, colon), p = rest.substr(colon + 1);
    int parts = 0;
    size_t i = 0;
    while (i <= a.size()) {
        const size_t dot = std::min(a.find('.', i), a.size());
        const std::string n = a.substr(i, dot - i);
        if (n.empty() || n.size() > 3 || !std::all_of(n.begin(), n.end(), ::isdigit) || std::stoi(n) > 255) return false;
        ++parts;
        i = dot + 1;
    }
    if (parts != 4 || p.empty() || p.size() > 5 || !std::all_of(p.begin(), p.end(), ::isdigit)) return false;
    const int v = std::stoi(p);
    if (v > 65535) return false;  // 0: a free port, said at start (tests)
    address = a;
    port = v;
    return true;
}

// "DEVICE@HOST[:PORT]" (VRPN's own form; the port defaults to VRPN's 3883). HOST is a name or an
// IPv4 address: letters, digits, '.', '-'.
bool parseVrpnServer(const std::string& s, std::string& device, std::string& host, int& port) {
    const size_t at = s.find('@');
    if (at == std::string::npos || at == 0 || at > 99) return false;  // VRPN's names are at most 99 characters
    device = s.substr(0, at);
    std::string rest = s.substr(at + 1);
    port = 3883;
    const size_t colon = rest.rfind(':');
    if (colon != std::string::npos) {
        const std::string p = rest.substr(colon + 1);
        if (p.empty() || p.size() > 5 || !std::all_of(p.begin(), p.end(), ::isdigit) || std::stoi(p) > 65535) return false;
        port = std::stoi(p);
        rest = rest.substr(0, colon);
    }
    if (rest.empty() || !std::all_of(rest.begin(), rest.end(), [](char c) { return std::isalnum((unsigned char)c) || c == '.' || c == '-'; }))
        return false;
    host = rest;
    return std::all_of(device.begin(), device.end(), [](char c) { return std::isprint((unsigned char)c) && c != ' '; });
}

}  // namespace

void readTracking(toml_reader::Reader& r, TrackingConfig& t) {
    t.enabled = true;
    t.source = r.string("source", t.source);
    if (t.source == "vrpn") {
        t.kind = TrackingSource::Vrpn;
        t.server = r.string("server", "", true);
        if (!parseVrpnServer(t.server, t.device, t.address, t.port))
            r.fail(r.find("server"), "key 'server': expected DEVICE@HOST or DEVICE@HOST:PORT (Tracker0@localhost), got '" + t.server + "'");
        t.buttonDevice = r.string("buttons", t.device);
        t.analogDevice = r.string("analog", t.device);
        for (const char* k : {"buttons", "analog"})
            if (r.has(k) && (r.string(k, "").empty() || r.string(k, "").size() > 99))
                r.fail(r.find(k), std::string("key '") + k + "': a VRPN device name of 1 to 99 characters");
        t.roomScale = 1.0;  // VRPN reports metres
    } else if (!parseSource(t.source, t.address, t.port)) {
        r.fail(r.find("source"), "key 'source': expected dtrack://ADDRESS:PORT with an IPv4 address to listen on and a UDP port "
                                 "(dtrack://0.0.0.0:5000), or \"vrpn\" with a server, got '" + t.source + "'");
    }
    for (const char* k : {"server", "buttons", "analog"})
        if (t.kind != TrackingSource::Vrpn && r.has(k))
            r.fail(r.find(k), std::string("key '") + k + "': a VRPN setting, but source is not \"vrpn\"");
    t.headBody = r.integer("head_body", t.headBody);
    t.flystick = r.integer("flystick", t.flystick);
    t.roomScale = r.number("room_scale", t.roomScale);
    if (t.roomScale <= 0) r.fail(r.find("room_scale"), "key 'room_scale': must be positive");
    t.roomRotate = r.vec3d("room_rotate", t.roomRotate);
    for (double a : t.roomRotate)
        if (std::fabs(a) > 360) r.fail(r.find("room_rotate"), "key 'room_rotate': angles are degrees in [-360, 360]");
    t.roomTranslate = r.vec3d("room_translate", t.roomTranslate);
    t.timeoutMs = r.integer("timeout_ms", t.timeoutMs);
    t.predictionMs = r.number("prediction_ms", t.predictionMs);
    t.filter = r.choice("filter", "none") == "one_euro" ? TrackingFilter::OneEuro : TrackingFilter::None;
    for (const char* k : {"min_cutoff", "beta", "derivative_cutoff"})
        if (t.filter == TrackingFilter::None && r.has(k))
            r.fail(r.find(k), std::string("key '") + k + "': a one-euro filter setting, but filter is \"none\" (set filter = \"one_euro\")");
    toml_reader::readFields<TrackingConfig>(
        r, t,
        {{"min_cutoff", &TrackingConfig::minCutoff}, {"beta", &TrackingConfig::beta},
         {"derivative_cutoff", &TrackingConfig::derivativeCutoff}, {"button_pick", &TrackingConfig::buttonPick},
         {"button_mode", &TrackingConfig::buttonMode}, {"button_home", &TrackingConfig::buttonHome},
         {"joystick_x", &TrackingConfig::joystickX}, {"joystick_y", &TrackingConfig::joystickY},
         {"fly_speed", &TrackingConfig::flySpeed}, {"turn_speed", &TrackingConfig::turnSpeed},
         {"dead_zone", &TrackingConfig::deadZone}});
    t.wandDirection = r.vec3d("wand_direction", t.wandDirection);
    const auto& d = t.wandDirection;
    if (!(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > 1e-12) || !std::isfinite(d[0] + d[1] + d[2]))
        r.fail(r.find("wand_direction"), "key 'wand_direction': must be a direction (not zero)");
    t.wandRay = r.boolean("wand_ray", t.wandRay);
    r.finish();
}

void readNavigation(toml_reader::Reader& r, NavigationConfig& n) {
    // The table's range keeps it positive and finite; a scale the floats of a pose cannot carry
    // (the room a millionth of a unit, or a million units a metre) is no use either.
    n.scale = r.number("scale", n.scale);
    r.finish();
}

}  // namespace rtwall
