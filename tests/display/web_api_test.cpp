// The operator console's API without a network or a wall (issue 31): WebApi over a FakeConsole
// whose changes never run. Every request needs the token; every bad request is a 4xx with a
// one-line reason and asks for no change at all.
#include "parts_scene.h"
#include "scratch.h"

#include <rtwall/web.h>
#include <rtwall/web_testing.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace rtwall {
namespace {

const std::string kToken = "0123456789abcdefTOKEN";

WebRequest get(const std::string& path, const std::string& auth = "Bearer " + kToken) {
    WebRequest q;
    q.method = "GET";
    q.path = path;
    q.authorization = auth;
    return q;
}
WebRequest post(const std::string& path, const std::string& body, const std::string& method = "POST") {
    WebRequest q = get(path);
    q.method = method;
    q.body = body;
    return q;
}

struct Api : ::testing::Test {
    testing::FakeConsole console{test::partsScene(), 96, 72};
    WebApi api{console, kToken};

    // A refusal: the status, one line of JSON with "error", and no change asked for.
    void refused(const WebRequest& q, int status, const std::string& says = "") {
        const int before = console.commands;
        const WebResponse r = api.handle(q);
        EXPECT_EQ(r.status, status) << q.method << " " << q.path << " " << q.body << ": " << r.body;
        EXPECT_EQ(r.body.find('\n'), std::string::npos) << r.body;
        const nlohmann::json j = nlohmann::json::parse(r.body, nullptr, false);
        ASSERT_TRUE(j.is_object() && j.contains("error")) << r.body;
        if (!says.empty()) {
            EXPECT_NE(j["error"].get<std::string>().find(says), std::string::npos) << r.body;
        }
        EXPECT_EQ(console.commands, before) << q.method << " " << q.path << " asked for a change";
    }
};

TEST_F(Api, EveryRequestNeedsTheToken) {
    for (const std::string path : {"/", "/index.html", "/console.js", "/api/status", "/api/parts", "/api/session", "/api/screenshot.png"}) {
        refused(get(path, ""), 401, "token");
        refused(get(path, "Bearer wrong"), 401);
        refused(get(path, "Bearer " + kToken + "x"), 401);
        refused(get(path, "Basic " + kToken), 401);
    }
    WebRequest change = post("/api/parts/1", R"({"visible": false})");
    change.authorization.clear();
    refused(change, 401);
    // The cookie the printed URL sets works as the header does.
    WebRequest c = get("/api/status", "");
    c.cookie = "other=1; rtwall_token=" + kToken + "; more=2";
    EXPECT_EQ(api.handle(c).status, 200);
    c.cookie = "rtwall_token=" + kToken.substr(1);
    refused(c, 401);
}

TEST_F(Api, ThePrintedUrlSetsTheCookieOnce) {
    WebRequest q = get("/", "");
    q.params["token"] = kToken;
    const WebResponse r = api.handle(q);
    EXPECT_EQ(r.status, 303);
    bool cookie = false;
    for (const auto& [k, v] : r.headers) cookie = cookie || (k == "Set-Cookie" && v.starts_with("rtwall_token=" + kToken + ";") &&
                                                              v.find("HttpOnly") != std::string::npos && v.find("SameSite=Strict") != std::string::npos);
    EXPECT_TRUE(cookie);
    q.params["token"] = "nope";
    refused(q, 401);
}

TEST_F(Api, ThePageAndTheStatus) {
    WebResponse r = api.handle(get("/"));
    ASSERT_EQ(r.status, 200);
    EXPECT_NE(r.contentType.find("text/html"), std::string::npos);
    EXPECT_NE(r.body.find("rtwall console"), std::string::npos);
    EXPECT_EQ(api.handle(get("/console.js")).status, 200);
    EXPECT_EQ(api.handle(get("/console.css")).status, 200);
    refused(get("/../etc/passwd"), 404);
    refused(post("/index.html", "x"), 405);
    r = api.handle(get("/api/status"));
    ASSERT_EQ(r.status, 200);
    const nlohmann::json j = nlohmann::json::parse(r.body);
    EXPECT_EQ(j["frame"], 7);
    EXPECT_TRUE(j["fps"].is_number());
    EXPECT_EQ(j["wall"]["width"], 96);
    r = api.handle(get("/api/parts"));
    ASSERT_EQ(r.status, 200);
    const nlohmann::json parts = nlohmann::json::parse(r.body)["parts"];
    ASSERT_EQ(parts.size(), 5u);  // asm, asm/left, asm/right, asm/right/knob, and the floor by its mesh's name
    EXPECT_EQ(parts[2]["path"], "asm/right");
    EXPECT_EQ(parts[0]["instances"], 3);
    EXPECT_EQ(parts[4]["path"], "floor");
}

TEST_F(Api, BadInputChangesNothing) {
    refused(post("/api/parts/5", R"({"visible": false})"), 404, "no part");
    refused(post("/api/parts/-1", R"({"visible": false})"), 404);
    refused(post("/api/parts/1x", R"({"visible": false})"), 404);
    refused(post("/api/parts/99999999999999999999", R"({"visible": false})"), 404);
    refused(post("/api/parts/1", "{"), 400, "not valid JSON");
    refused(post("/api/parts/1", ""), 400);
    refused(post("/api/parts/1", "[1]"), 400, "object");
    refused(post("/api/parts/1", R"({"visible": "no"})"), 400, "true or false");
    refused(post("/api/parts/1", R"({"visbile": false})"), 400, "unknown key 'visbile'");
    refused(post("/api/parts/1", R"({})"), 400);
    refused(post("/api/parts", R"({"show_all": false})"), 400);
    refused(post("/api/sections", R"({"normal": [0, 0, 0], "offset": 1})"), 400, "zero");
    refused(post("/api/sections", R"({"normal": [1, 0], "offset": 1})"), 400, "3 numbers");
    refused(post("/api/sections", R"({"normal": [1, 0, NaN], "offset": 1})"), 400);
    refused(post("/api/sections", R"({"normal": [1, 0, 0], "offset": 1e999})"), 400);
    refused(post("/api/sections", R"({"normal": [1, 0, 0], "offset": 1e300})"), 400, "finite");
    refused(post("/api/sections", R"({"normal": [1, 0, 0]})"), 400, "offset");
    refused(post("/api/sections", R"({"normal": [1, 0, 0], "offset": "0"})"), 400);
    refused(post("/api/sections/0", R"({"flip": true})"), 404, "no section plane");  // slot 0 is not in use
    refused(post("/api/sections/0", "", "DELETE"), 404);
    refused(post("/api/sections/6", "", "DELETE"), 404);
    refused(post("/api/bookmarks", R"({"name": ""})"), 400);
    refused(post("/api/bookmarks", R"({"name": "a\u0000b"})"), 400, "control");
    refused(post("/api/bookmarks", nlohmann::json{{"name", std::string(201, 'x')}}.dump()), 400);
    refused(post("/api/bookmarks/1/go", "{}"), 404);
    refused(post("/api/bookmarks/0/go", R"({"seconds": -1})"), 400);
    refused(post("/api/bookmarks/0/fly", "{}"), 405);
    refused(post("/api/camera", R"({"position": [0, 0, 1], "target": [0, 0, 1]})"), 400, "differ");
    refused(post("/api/camera", R"({"position": [0, 0, 1], "target": [0, 0, 0], "up": [0, 0, 0]})"), 400);
    refused(post("/api/camera", R"({"position": [0, 0, 1e16], "target": [0, 0, 0]})"), 400);
    refused(post("/api/camera", R"({"position": [0, 0, 1]})"), 400);
    refused(post("/api/measurements", R"({"a": [10, 10], "b": [96, 10]})"), 400, "on the wall");
    refused(post("/api/measurements", R"({"a": [10, 10]})"), 400);
    refused(post("/api/measurements", R"({"a": [10, 10], "b": [1, "y"]})"), 400);
    refused(post("/api/measurements/1", "", "DELETE"), 404);
    refused(post("/api/session", "[camera]\nposition = [0, 0, 5]\n"), 400, "look_at");
    refused(post("/api/session", "[camera\n"), 400, "session:");
    refused(post("/api/session", "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[moved]]\ninstance = 4\n"
                                 "transform = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]\n"), 400, "does not exist");
    refused(post("/api/session", "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[parts]\nhide = [\"nothing\"]\n"), 400, "nothing");
    WebRequest shot = get("/api/screenshot.png");
    shot.params["eye"] = "right";
    refused(shot, 400, "not stereo");
    shot.params["eye"] = "middle";
    refused(shot, 400, "left or right");
    refused(post("/api/status", "{}", "PUT"), 405);
    refused(get("/api/nothing"), 404);
    refused(get("/api/thumbnail.jpg"), 503);  // the fake has none
}

TEST_F(Api, AGoodChangeIsPostedOnce) {
    const WebResponse r = api.handle(post("/api/parts/1", R"({"visible": false})"));
    EXPECT_EQ(r.status, 503);  // the fake never runs it: "did not take the change"
    EXPECT_EQ(console.commands, 1);
    EXPECT_EQ(api.handle(post("/api/sections", R"({"normal": [0, 2, 0], "offset": 0.5})")).status, 503);
    EXPECT_EQ(console.commands, 2);
}

TEST(WebConfig, TheRunConfigsWebTable) {
    const auto dir = test::scratchDir();
    auto write = [&](const std::string& text) {
        std::ofstream(dir / "run.toml") << text;
        return dir / "run.toml";
    };
    RunConfig c = readRunConfig(write("[run]\nsession = \"s.toml\"\n[web]\naddress = \"0.0.0.0\"\nport = 0\n"
                                      "token = \"abcdefghijklmnop-_.~\"\ncertificate = \"c.pem\"\nkey = \"k.pem\"\n"
                                      "thumbnails_per_second = 2\nthumbnail_width = 320\n"));
    EXPECT_TRUE(c.web.enabled);
    EXPECT_EQ(c.web.address, "0.0.0.0");
    EXPECT_EQ(c.web.port, 0);
    EXPECT_EQ(c.web.token, "abcdefghijklmnop-_.~");
    EXPECT_EQ(c.web.certificate, dir / "c.pem");  // relative to the config
    EXPECT_EQ(c.web.key, dir / "k.pem");
    EXPECT_EQ(c.web.thumbnailsPerSecond, 2.0);
    EXPECT_EQ(c.web.thumbnailWidth, 320);
    EXPECT_EQ(c.session, dir / "s.toml");
    EXPECT_FALSE(readRunConfig(write("scene = \"builtin:knots\"\n")).web.enabled);  // no table: no console
    EXPECT_FALSE(readRunConfig(write("[web]\nenabled = false\n")).web.enabled);
    auto refused = [&](const std::string& text, const std::string& says) {
        try {
            readRunConfig(write(text));
            ADD_FAILURE() << "accepted: " << text;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
            EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
        }
    };
    refused("[web]\ntoken = \"0123456789abcdef ghij\"\n", "key 'token'");
    refused("[web]\ncertificate = \"c.pem\"\n", "both 'certificate' and 'key'");
    refused("[web]\nport = 70000\n", "port");
    refused("[web]\nthumbnails_per_second = 0\n", "thumbnails_per_second");
    refused("[web]\nadress = \"127.0.0.1\"\n", "unknown key 'adress'");
}

}  // namespace
}  // namespace rtwall
