// libFuzzer target for the operator console's request and JSON handlers (display/web/src/
// web_api.cpp, and the session files of display/wall/src/session_file.cpp it parses): every
// request a browser, a script or an attacker can send to `rtwall run --web`, against the parts
// scene, through a FakeConsole whose changes never run.
//
// The input: "METHOD\nPATH[?QUERY]\nAUTH\nBODY", AUTH "1" for the right token, else the
// Authorization header as given. Besides the sanitizers it checks that every answer is a status
// of 200..599, that a refusal (4xx, 5xx) is one line of JSON with "error", that no request
// without the token gets anything but 401 (or the printed URL's 303), and that a refused
// request asked for no change.
//
// With CMake: -DCMAKE_CXX_COMPILER=clang++ -DRTWALL_FUZZ=ON, target fuzz_web. Run by hand:
//   build-fuzz/tests/fuzz/fuzz_web -max_total_time=120 build-fuzz/tests/fuzz/corpus/web tests/fuzz/corpus/web
#include "../parts_scene.h"

#include <rtwall/web.h>
#include <rtwall/web_testing.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

using namespace rtwall;

namespace {
[[noreturn]] void finding(const char* what, const std::string& detail) {
    std::fprintf(stderr, "fuzz_web: %s: %s\n", what, detail.substr(0, 300).c_str());
    std::abort();
}
const std::string kToken = "fuzz-token-0123456789";
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static testing::FakeConsole console(test::partsScene(), 96, 72);
    static WebApi api(console, kToken, std::chrono::milliseconds(5000), std::chrono::milliseconds(0));  // no screenshot pacing: no sleeps
    const std::string in(reinterpret_cast<const char*>(data), size);
    std::string fields[3];
    size_t at = 0;
    for (std::string& f : fields) {
        const size_t nl = in.find('\n', at);
        if (nl == std::string::npos) return 0;
        f = in.substr(at, nl - at);
        at = nl + 1;
    }
    WebRequest q;
    q.method = fields[0];
    q.path = fields[1];
    if (const size_t mark = q.path.find('?'); mark != std::string::npos) {
        const std::string query = q.path.substr(mark + 1);
        q.path.resize(mark);
        size_t i = 0;
        while (i <= query.size()) {
            size_t amp = query.find('&', i);
            if (amp == std::string::npos) amp = query.size();
            const std::string item = query.substr(i, amp - i);
            const size_t eq = item.find('=');
            q.params[item.substr(0, eq)] = eq == std::string::npos ? "" : item.substr(eq + 1);
            i = amp + 1;
        }
    }
    const bool token = fields[2] == "1";
    q.authorization = token ? "Bearer " + kToken : fields[2];
    q.body = in.substr(at);
    const int before = console.commands;
    const WebResponse r = api.handle(q);
    if (r.status < 200 || r.status > 599) finding("a status out of range", std::to_string(r.status));
    if (!token && r.status != 401 && r.status != 303) finding("an answer without the token", q.method + " " + q.path + " -> " + std::to_string(r.status));
    if (r.status >= 400) {
        if (r.body.find('\n') != std::string::npos) finding("a refusal of more than one line", r.body);
        const nlohmann::json j = nlohmann::json::parse(r.body, nullptr, false);
        if (!j.is_object() || !j.contains("error") || !j["error"].is_string()) finding("a refusal without {\"error\": ...}", r.body);
        // 503: the fake never runs a change, so an accepted change says the wall did not take it.
        if (r.status != 503 && console.commands != before) finding("a refused request asked for a change", q.method + " " + q.path);
    }
    return 0;
}
