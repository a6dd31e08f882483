// The operator console against a wall (issue 31): real HTTP requests on loopback to the server
// of a stepped WallSession (its clients on threads), the session stepping on a thread of its
// own as `rtwall run` does. Changes from the API equal the same changes by key, bit for bit;
// a saved session restores the same frame; attackers never stop the frames.
#include "display_test_util.h"
#include "files.h"
#include "parts_scene.h"
#include "session_test_util.h"

#include <rtwall/image_box.h>
#include <rtwall/web.h>
#include <rtwall/web_testing.h>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <future>
#include <thread>

namespace rtwall {
namespace {

using nlohmann::json;

const std::string kToken = "test-token-0123456789";

// A session with its console, stepping on its own thread until destroyed.
struct Console {
    std::shared_ptr<std::vector<std::string>> lines = std::make_shared<std::vector<std::string>>();
    std::unique_ptr<WallSession> session;
    std::unique_ptr<ConsoleBackend> backend;
    std::unique_ptr<WebApi> api;
    std::unique_ptr<WebServer> server;
    std::atomic<bool> stop{false};
    std::atomic<uint64_t> steps{0};
    std::thread stepper;
    std::filesystem::path dir;

    explicit Console(RunConfig c, WebServer::Limits limits = {}) {
        auto mutex = std::make_shared<std::mutex>();
        c.log = [kept = lines, mutex](const std::string& line) {
            std::lock_guard<std::mutex> lock(*mutex);
            kept->push_back(line);
        };
        dir = c.out;
        session = std::make_unique<WallSession>(c);
        WebSettings w;
        w.enabled = true;
        w.port = 0;
        w.token = kToken;
        w.thumbnailsPerSecond = 30;
        backend = sessionBackend(*session, w);
        api = std::make_unique<WebApi>(*backend, kToken, std::chrono::milliseconds(20000));
        server = std::make_unique<WebServer>(*api, w, limits, [](const std::string&) {});
        stepper = std::thread([this] {
            while (!stop && session->step()) {
                ++steps;
                std::this_thread::sleep_for(std::chrono::milliseconds(2));
            }
        });
    }
    ~Console() {
        stop = true;
        stepper.join();
        server.reset();
        backend.reset();
        session.reset();
    }
    httplib::Client client() const {
        httplib::Client c("127.0.0.1", server->port());
        c.set_bearer_token_auth(kToken.c_str());
        c.set_read_timeout(30, 0);
        return c;
    }
    // The wall's frame now, as the screenshot endpoint gives it (PNG decoded).
    Image screenshot() {
        httplib::Client c = client();
        const auto r = c.Get("/api/screenshot.png");
        EXPECT_TRUE(r && r->status == 200);
        if (!r) return {};
        const std::filesystem::path f = dir / "shot.png";
        std::ofstream(f, std::ios::binary) << r->body;
        return readPng(f);
    }
    // Waits until the frames after a change show it: two more steps.
    void settle() {
        const uint64_t at = steps;
        for (int i = 0; i < 20000 && steps < at + 3; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
};

// The parts scene with its boxes lifted off the floor and the knob off its box: no faces on
// one plane. Where faces coincide (a box standing on the floor) a section's cap pixels depend on
// the history of updates, not only the state (a debt of the engine's two top levels, found here:
// the same session state rendered 3 cap pixels apart after a restore), which a session file
// cannot bring back.
SceneDesc liftedPartsScene() {
    SceneDesc d = test::partsScene();
    d.instances[1].transform = Transform::translate(0, 0.05, 0) * d.instances[1].transform;
    d.instances[2].transform = Transform::translate(0, 0.05, 0) * d.instances[2].transform;
    d.instances[3].transform = Transform::translate(0, 0.1, 0) * d.instances[3].transform;
    return d;
}

RunConfig partsConfig() {
    RunConfig c = steppedRunConfig(test::scratchDir());
    c.scene = "parts";
    c.loaded = liftedPartsScene();
    c.cluster.async = false;
    return c;
}

json body(const httplib::Result& r) {
    EXPECT_TRUE(r);
    if (!r) return {};
    return json::parse(r->body, nullptr, false);
}

TEST(WebConsole, TokenAndStatusOverHttp) {
    Console w(partsConfig());
    httplib::Client anon("127.0.0.1", w.server->port());
    auto r = anon.Get("/api/status");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 401);
    r = anon.Get("/");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 401);
    httplib::Client c = w.client();
    w.settle();
    const json s = body(c.Get("/api/status"));
    EXPECT_GT(s["frame"].get<int>(), 0);
    EXPECT_GT(s["fps"].get<double>(), 0);
    EXPECT_EQ(s["clients"].size(), 2u);
    // The thumbnail follows the frames.
    r = c.Get("/api/thumbnail.jpg");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200);
    EXPECT_EQ(r->get_header_value("Content-Type"), "image/jpeg");
    EXPECT_EQ(uint8_t(r->body[0]), 0xFF);
    EXPECT_EQ(uint8_t(r->body[1]), 0xD8);
    // The printed URL: the cookie, then the page with it.
    httplib::Client browser("127.0.0.1", w.server->port());
    r = browser.Get(("/?token=" + kToken).c_str());
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 303);
    const std::string cookie = r->get_header_value("Set-Cookie");
    r = browser.Get("/", {{"Cookie", cookie.substr(0, cookie.find(';'))}});
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    EXPECT_NE(r->body.find("rtwall console"), std::string::npos);
}

TEST(WebConsole, HidingAPartByTheApiIsHidingItByKey) {
    Console w(partsConfig());
    httplib::Client c = w.client();
    w.settle();
    const Image before = w.screenshot();
    const json parts = body(c.Get("/api/parts"))["parts"];
    ASSERT_EQ(parts[1]["path"], "asm/left");
    json r = body(c.Post("/api/parts/1", R"({"visible": false})", "application/json"));
    EXPECT_EQ(r["visible"], false);
    EXPECT_EQ(r["hidden"], 1);
    w.settle();
    const Image byApi = w.screenshot();
    EXPECT_GT(test::differingBytes(byApi, before), 0u);
    // Show all, then the same by key: Ctrl+click on the left box, X.
    ASSERT_EQ(c.Post("/api/parts", R"({"show_all": true})", "application/json")->status, 200);
    w.settle();
    EXPECT_EQ(test::differingBytes(w.screenshot(), before), 0u);
    std::promise<std::pair<double, double>> at;
    w.session->post([&at](WallSession& s) {
        const RenderSettings& st = s.scene().settings;
        for (int y = 0; y < st.height; ++y)
            for (int x = 0; x < st.width; ++x)
                if (const auto hit = s.pick(x + 0.5, y + 0.5); hit && hit->instance == 1) return at.set_value({x + 0.5, y + 0.5});
        at.set_value({-1, -1});
    });
    const auto [x, y] = at.get_future().get();
    ASSERT_GE(x, 0);
    w.session->post([x = x, y = y](WallSession& s) {
        s.inject(test::ctrlClick({x, y}));
        s.inject(test::keyPress(GLFW_KEY_X));
    });
    w.settle();
    w.settle();
    EXPECT_EQ(test::differingBytes(w.screenshot(), byApi), 0u) << "the key's hide and the API's differ";
    // And the frame is the state rendered on one machine.
    std::promise<size_t> off;
    w.session->post([&off](WallSession& s) { off.set_value(test::bytesOffState(s)); });
    EXPECT_EQ(off.get_future().get(), 0u);

    // Isolate the right box's node (the box and its knob), then not.
    json part = body(c.Post("/api/parts/2", R"({"isolate": true})", "application/json"));
    EXPECT_EQ(part["hidden"], 0);
    json view = body(c.Get("/api/parts"))["view"];
    EXPECT_EQ(view["isolate"], json::array({"asm/right"}));
    json all = body(c.Get("/api/parts"))["parts"];
    EXPECT_EQ(all[4]["visible"], false);  // the floor
    EXPECT_EQ(all[3]["visible"], true);   // the knob, under asm/right
    body(c.Post("/api/parts/2", R"({"isolate": false})", "application/json"));
    EXPECT_EQ(body(c.Get("/api/parts"))["view"]["isolate"].size(), 0u);
}

TEST(WebConsole, TheEventStreamSendsTheStatusOfNewFramesAndSaysWhenTheStateChanged) {
    Console w(partsConfig());
    httplib::Client c = w.client();
    std::string got;
    int events = 0, states = 0;
    std::thread changer;
    auto r = c.Get("/api/events", [&](const char* data, size_t n) {
        got.append(data, n);
        size_t at;
        while ((at = got.find("\n\n")) != std::string::npos) {
            const std::string event = got.substr(0, at);
            got.erase(0, at + 2);
            if (event.starts_with("event: state\n")) ++states;
            if (!event.starts_with("event: status\ndata: ")) continue;
            const json s = json::parse(event.substr(20), nullptr, false);
            EXPECT_TRUE(s.contains("fps") && s.contains("frame")) << event;
            if (++events == 3)  // then a change from another client (as a key's would be)
                changer = std::thread([&w] { w.client().Post("/api/parts/1", R"({"visible": false})", "application/json"); });
        }
        return states == 0 && events < 200;  // then the client hangs up
    });
    changer.join();
    EXPECT_GE(events, 3);
    EXPECT_EQ(states, 1);
}

TEST(WebConsole, SectionsBookmarksCameraMeasurements) {
    Console w(partsConfig());
    httplib::Client c = w.client();
    w.settle();
    // Sections: add (the plane n.p = d), move, flip, remove; at most six.
    json s = body(c.Post("/api/sections", R"({"normal": [2, 0, 0], "offset": 0.5})", "application/json"));
    EXPECT_EQ(s["id"], 0);
    EXPECT_DOUBLE_EQ(s["normal"][0].get<double>(), 1.0);
    EXPECT_NEAR(s["offset"].get<double>(), 0.5, 1e-6);
    w.settle();
    const Image cut = w.screenshot();
    s = body(c.Post("/api/sections/0", R"({"offset": -0.25})", "application/json"));
    EXPECT_NEAR(s["offset"].get<double>(), -0.25, 1e-6);
    s = body(c.Post("/api/sections/0", R"({"flip": true})", "application/json"));
    EXPECT_DOUBLE_EQ(s["normal"][0].get<double>(), -1.0);
    EXPECT_NEAR(s["offset"].get<double>(), 0.25, 1e-6);
    EXPECT_EQ(body(c.Get("/api/sections"))["sections"].size(), 1u);
    for (int i = 1; i < kMaxSections; ++i)
        EXPECT_EQ(body(c.Post("/api/sections", R"({"normal": [0, 1, 0], "offset": -5})", "application/json"))["id"], i);
    auto full = c.Post("/api/sections", R"({"normal": [0, 1, 0], "offset": -5})", "application/json");
    ASSERT_TRUE(full);
    EXPECT_EQ(full->status, 409);
    for (int i = 0; i < kMaxSections; ++i) EXPECT_EQ(c.Delete(("/api/sections/" + std::to_string(i)).c_str())->status, 200);
    EXPECT_EQ(body(c.Get("/api/sections"))["sections"].size(), 0u);
    w.settle();
    const Image open = w.screenshot();
    EXPECT_GT(test::differingBytes(cut, open), 0u);

    // Camera and bookmarks: save this view, go elsewhere, come back at once.
    const json start = body(c.Get("/api/camera"));
    EXPECT_EQ(body(c.Post("/api/bookmarks", R"({"name": "start"})", "application/json"))["id"], 0);
    json cam = body(c.Post("/api/camera", R"({"position": [3, 2, 5], "target": [0, 0.5, 0], "up": [0, 1, 0]})", "application/json"));
    EXPECT_EQ(cam["camera"]["position"], json({3, 2, 5}));
    w.settle();
    EXPECT_GT(test::differingBytes(w.screenshot(), open), 0u);
    EXPECT_EQ(body(c.Post("/api/bookmarks/0/go", R"({"seconds": 0})", "application/json"))["going"], "start");
    w.settle();
    EXPECT_EQ(body(c.Get("/api/camera")), start);
    EXPECT_EQ(test::differingBytes(w.screenshot(), open), 0u);
    // Smoothly: the flight ends where the bookmark is.
    c.Post("/api/camera", R"({"position": [3, 2, 5], "target": [0, 0.5, 0]})", "application/json");
    ASSERT_EQ(c.Post("/api/bookmarks/0/go", R"({"seconds": 0.3})", "application/json")->status, 200);
    for (int i = 0; i < 400 && body(c.Get("/api/status"))["flying"] != false; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    w.settle();
    EXPECT_EQ(body(c.Get("/api/camera")), start);
    EXPECT_EQ(c.Delete("/api/bookmarks/0")->status, 200);
    EXPECT_EQ(body(c.Get("/api/bookmarks"))["bookmarks"].size(), 0u);

    // Measurements: two wall pixels on the floor, in front of and behind the boxes.
    json m = body(c.Post("/api/measurements", R"({"a": [48, 66], "b": [48, 40]})", "application/json"));
    ASSERT_TRUE(m.contains("distance")) << m.dump();
    EXPECT_GT(m["distance"].get<double>(), 0.5);
    EXPECT_EQ(body(c.Get("/api/measurements"))["measurements"].size(), 1u);
    auto sky = c.Post("/api/measurements", R"({"a": [1, 1], "b": [48, 40]})", "application/json");  // the top left corner shows nothing
    ASSERT_TRUE(sky);
    EXPECT_EQ(sky->status, 422);
    EXPECT_EQ(c.Delete("/api/measurements/0")->status, 200);
    EXPECT_EQ(body(c.Get("/api/measurements"))["measurements"].size(), 0u);
}

TEST(WebConsole, ASavedSessionRestoresTheSameFrame) {
    std::string saved;
    Image shown;
    {
        Console w(partsConfig());
        httplib::Client c = w.client();
        w.settle();
        ASSERT_EQ(c.Post("/api/measurements", R"({"a": [48, 66], "b": [48, 40]})", "application/json")->status, 200);
        ASSERT_EQ(c.Post("/api/camera", R"({"position": [2.5, 3, 4], "target": [0.2, 0.4, 0]})", "application/json")->status, 200);
        ASSERT_EQ(c.Post("/api/sections", R"({"normal": [0, 0, -1], "offset": -0.1})", "application/json")->status, 200);
        ASSERT_EQ(c.Post("/api/parts/3", R"({"visible": false})", "application/json")->status, 200);  // the knob
        ASSERT_EQ(c.Post("/api/parts/1", R"({"highlight": true})", "application/json")->status, 200);
        ASSERT_EQ(c.Post("/api/bookmarks", R"({"name": "review \"A\""})", "application/json")->status, 200);
        // An instance moved (as a drag moves it).
        std::promise<void> moved;
        w.session->post([&moved](WallSession& s) {
            s.setInstanceTransform(2, Transform::translate(1.0, 0.9, 0.4) * Transform::scale(0.6, 0.6, 0.6));
            moved.set_value();
        });
        moved.get_future().get();
        w.settle();
        shown = w.screenshot();
        const auto r = c.Get("/api/session");
        ASSERT_TRUE(r);
        ASSERT_EQ(r->status, 200);
        saved = r->body;
        EXPECT_NE(saved.find("[[moved]]"), std::string::npos);
        // Change everything, then restore: the same frame, bit for bit.
        c.Post("/api/camera", R"({"position": [0, 5, 7], "target": [0, 0, 0]})", "application/json");
        c.Post("/api/parts", R"({"show_all": true})", "application/json");
        c.Delete("/api/sections/0");
        w.settle();
        EXPECT_GT(test::differingBytes(w.screenshot(), shown), 0u);
        const json restored = body(c.Post("/api/session", saved, "application/toml"));
        EXPECT_EQ(restored["restored"], true) << restored.dump();
        w.settle();
        EXPECT_EQ(test::differingBytes(w.screenshot(), shown), 0u);
        EXPECT_EQ(body(c.Get("/api/bookmarks"))["bookmarks"][0]["name"], "review \"A\"");
        EXPECT_EQ(body(c.Get("/api/measurements"))["measurements"].size(), 1u);
        EXPECT_EQ(c.Get("/api/session")->body, saved);
    }
    // rtwall run --session FILE: the first frame is that frame.
    RunConfig cfg = partsConfig();
    const std::filesystem::path file = cfg.out / "review.toml";
    std::ofstream(file) << saved;
    cfg.session = file;
    WallSession s(cfg);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(test::differingBytes(s.lastFrame().left, shown), 0u);
    EXPECT_EQ(writeSessionState(s.sessionState(), s.scene()), saved);
}

// The JPEG's size from its frame header (SOF0, baseline as libjpeg-turbo writes it).
std::pair<int, int> jpegSize(const std::string& j) {
    for (size_t i = 2; i + 9 < j.size(); ++i)
        if (uint8_t(j[i]) == 0xFF && uint8_t(j[i + 1]) == 0xC0)
            return {int(uint8_t(j[i + 7])) << 8 | uint8_t(j[i + 8]), int(uint8_t(j[i + 5])) << 8 | uint8_t(j[i + 6])};
    return {0, 0};
}

TEST(WebConsole, AStereoWallsThumbnailShowsBothEyesAndEachEyeHasItsScreenshot) {
    RunConfig c = partsConfig();
    c.wall = test::writeFile(c.out / "stereo.toml",
                             "[wall]\nwidth = 192\nheight = 144\n[stereo]\nmode = \"passive\"\neye_separation = 0.065\n"
                             "viewer = [0.0, 0.0, 2.5]\nlower_left = [-1.6, -1.2, 0.0]\nlower_right = [1.6, -1.2, 0.0]\n"
                             "upper_left = [-1.6, 1.2, 0.0]\n[[screen]]\nviewport = [0, 0, 192, 144]\neye = \"left\"\n"
                             "[[screen]]\nviewport = [0, 0, 192, 144]\neye = \"right\"\nwindow = [192, 0]\n");
    Console w(c);
    httplib::Client h = w.client();
    w.settle();
    EXPECT_EQ(body(h.Get("/api/status"))["wall"]["stereo"], true);
    auto r = h.Get("/api/thumbnail.jpg");
    ASSERT_TRUE(r && r->status == 200);
    EXPECT_EQ(jpegSize(r->body), std::make_pair(2 * 192, 144));  // the eyes side by side, each at the wall's width (under 480)
    auto left = h.Get("/api/screenshot.png?eye=left"), right = h.Get("/api/screenshot.png?eye=right");
    ASSERT_TRUE(left && right);
    ASSERT_EQ(left->status, 200);
    ASSERT_EQ(right->status, 200);
    EXPECT_NE(left->body, right->body);  // the eyes see the boxes from 6.5 cm apart
    // The right eye's PNG is the right eye's frame (a still view: every frame the same bytes).
    const std::filesystem::path file = w.dir / "right.png";
    std::ofstream(file, std::ios::binary) << right->body;
    std::promise<Image> eye;
    w.session->post([&eye](WallSession& s) { eye.set_value(s.lastFrame().right); });
    EXPECT_EQ(test::differingBytes(readPng(file), eye.get_future().get()), 0u);
}

// A wall on display nodes (the shipped two-node 2x2 wall, its nodes threads of this process;
// mono, and stereo side by side): the master holds no pixels, the console's pictures are the
// nodes'. Each pixel is summed by one node, so the picture is the one-PC wall's frame
// box-filtered over the pixels some screen shows (those under the bezels, shown by none, left
// out), byte for byte; the screenshot is that frame with its bezel pixels black, byte for byte.
class WebConsoleOnNodes : public ::testing::TestWithParam<bool> {};

TEST_P(WebConsoleOnNodes, ThumbnailAndScreenshotAreTheOnePcWallsPixelsThatTheScreensShow) {
    const bool stereo = GetParam();
    RunConfig c = partsConfig();
    std::string text = test::fileBytes(test::sourceDir() / "configs/wall/two-nodes-2x2.toml");
    const size_t writes = text.find("write_every = 1");
    ASSERT_NE(writes, std::string::npos);
    text.replace(writes, 15, "write_every = 0");  // the nodes write no PNGs
    if (stereo)
        text.insert(0, "[stereo]\nmode = \"side_by_side\"\neye_separation = 0.065\nviewer = [0.0, 0.0, 2.5]\n"
                       "lower_left = [-1.6, -1.2, 0.0]\nlower_right = [1.6, -1.2, 0.0]\nupper_left = [-1.6, 1.2, 0.0]\n\n");
    c.wall = test::writeFile(c.out / "nodes.toml", text);
    const WallConfig nodes = loadWallConfig(c.wall);
    WallConfig single = nodes;
    for (ScreenConfig& sc : single.screens) sc.node.clear();
    RunConfig one = c;  // partsConfig() again would empty the scratch directory
    one.out = c.out / "one";
    one.wall = test::writeFile(c.out / "one.toml", writeWallConfig(single));

    // The one-PC wall's frame (a still view: every frame the same bytes).
    WallFrame frame;
    {
        Console w(one);
        w.settle();
        std::promise<WallFrame> f;
        w.session->post([&f](WallSession& s) { f.set_value(s.lastFrame()); });
        frame = f.get_future().get();
    }
    ASSERT_EQ(frame.left.width, nodes.width);
    ASSERT_EQ(frame.right.rgb.empty(), !stereo);

    Console w(c);
    httplib::Client h = w.client();
    w.settle();
    EXPECT_EQ(body(h.Get("/api/status"))["wall"]["on_nodes"], true);
    const TileRouting routing(nodes, nodes.width, nodes.height);
    for (int eye = 0; eye < (stereo ? 2 : 1); ++eye) {
        SCOPED_TRACE(eye ? "right eye" : "left eye");
        const Image& im = eye ? frame.right : frame.left;
        const std::vector<uint8_t> owners = routing.owners(eye, 3);
        // The picture at the console's thumbnail width, straight from the session.
        const std::optional<NodePicture> pic = w.session->nodePicture(480, std::chrono::seconds(20));
        ASSERT_TRUE(pic);
        EXPECT_TRUE(pic->missing.empty());
        EXPECT_TRUE(pic->oneFrame);
        EXPECT_GT(pic->frame, 0u);
        const BoxGrid g = boxGrid(im.width, im.height, 480);
        std::vector<uint32_t> sums(g.cells() * 4, 0);
        for (uint8_t node : {0, 1}) addBoxSums(im, g, owners.data(), node, sums.data());
        const Image expected = boxMeans(g, sums.data());
        EXPECT_EQ(test::differingBytes(eye ? pic->right : pic->left, expected), 0u);
        EXPECT_EQ(pic->right.rgb.empty(), !stereo);
        // The screenshot: every pixel, those under the bezels black.
        Image shot = im;
        for (size_t p = 0; p < owners.size(); ++p)
            if (owners[p] == 0xFF) std::fill_n(shot.rgb.begin() + long(p * 3), 3, uint8_t(0));
        auto r = h.Get(eye ? "/api/screenshot.png?eye=right" : "/api/screenshot.png");
        ASSERT_TRUE(r);
        ASSERT_EQ(r->status, 200) << r->body;
        const std::filesystem::path file = w.dir / "shot.png";
        std::ofstream(file, std::ios::binary) << r->body;
        EXPECT_EQ(test::differingBytes(readPng(file), shot), 0u);
    }
    // The thumbnail over HTTP: the eyes side by side, 480 wide each (the console's width).
    auto r = h.Get("/api/thumbnail.jpg");
    ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "no answer");
    EXPECT_EQ(jpegSize(r->body), std::make_pair((stereo ? 2 : 1) * 480, 480 * nodes.height / nodes.width));
}

INSTANTIATE_TEST_SUITE_P(MonoAndStereo, WebConsoleOnNodes, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "Stereo" : "Mono"; });

// A raw connection that sends `request` and never reads.
int stalledReader(int port, const std::string& request) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    const int small = 4096;
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(uint16_t(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return -1;
    ::send(fd, request.data(), request.size(), 0);
    return fd;
}

TEST(WebConsole, AttackersDoNotStopTheWall) {
    WebServer::Limits limits;
    limits.requestsPerSecond = 20;
    limits.maxBody = 64 << 10;
    limits.writeTimeout = std::chrono::milliseconds(500);
    limits.maxStreams = 2;
    RunConfig cfg = partsConfig();
    cfg.width = 640;  // a screenshot larger than the socket buffers
    cfg.height = 480;
    Console w(cfg, limits);
    w.settle();
    const int port = w.server->port();
    // Readers that never read: a screenshot and two event streams; a third stream is refused.
    const std::string auth = "Authorization: Bearer " + kToken + "\r\n";
    std::vector<int> stalled;
    stalled.push_back(stalledReader(port, "GET /api/screenshot.png HTTP/1.1\r\nHost: x\r\n" + auth + "\r\n"));
    for (int i = 0; i < 2; ++i) stalled.push_back(stalledReader(port, "GET /api/events HTTP/1.1\r\nHost: x\r\n" + auth + "\r\n"));
    for (int fd : stalled) ASSERT_GE(fd, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    {
        httplib::Client c = w.client();
        auto r = c.Get("/api/events");
        ASSERT_TRUE(r);
        EXPECT_EQ(r->status, 503);
    }
    // A flood, requests without the token, oversized and malformed bodies, all at once.
    const uint64_t stepsBefore = w.steps;
    std::atomic<int> ok{0}, tooMany{0}, unauthorized{0}, tooLarge{0}, bad{0}, other{0}, dropped{0};
    std::vector<std::thread> attackers;
    for (int t = 0; t < 3; ++t)
        attackers.emplace_back([&, t] {
            httplib::Client c("127.0.0.1", port);
            c.set_read_timeout(10, 0);
            if (t != 1) c.set_bearer_token_auth(kToken.c_str());
            for (int i = 0; i < 150; ++i) {
                httplib::Result r = t == 2 ? (i % 2 ? c.Post("/api/sections", std::string(100 << 10, '{'), "application/json")
                                                    : c.Post("/api/sections", R"({"normal": [1, 0, 0], "offset": NaN})", "application/json"))
                                           : c.Get("/api/status");
                if (!r) {  // the server closed on an oversized body before it was all sent
                    ++dropped;
                    continue;
                }
                switch (r->status) {
                case 200: ++ok; break;
                case 429: ++tooMany; break;
                case 401: ++unauthorized; break;
                case 413: ++tooLarge; break;
                case 400: ++bad; break;
                default: ++other;
                }
            }
        });
    for (std::thread& t : attackers) t.join();
    EXPECT_GT(ok, 0);
    EXPECT_GT(tooMany, 0);
    EXPECT_GT(unauthorized, 0);
    EXPECT_GT(tooLarge + bad + dropped, 0);
    EXPECT_EQ(other, 0) << "answers other than 200, 400, 401, 413 and 429";
    EXPECT_GT(w.server->refused(), 0u);
    // The frames went on through all of it, and the console still answers.
    w.settle();
    EXPECT_GE(w.steps, stepsBefore + 3);
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));  // the rate limit's bucket refills
    httplib::Client c = w.client();
    auto r = c.Get("/api/status");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    EXPECT_EQ(body(c.Get("/api/sections"))["sections"].size(), 0u);  // no attacker changed anything
    for (int fd : stalled) ::close(fd);
}

TEST(WebServer, RefusesANonLoopbackAddressWithoutTls) {
    WebSettings w;
    w.address = "0.0.0.0";
    try {
        checkWebSettings(w);
        ADD_FAILURE() << "0.0.0.0 without TLS was accepted";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "web: 0.0.0.0 is not loopback: give [web] certificate and key (TLS), or --web-insecure");
    }
    w.insecure = true;
    EXPECT_NO_THROW(checkWebSettings(w));
    w.insecure = false;
    w.certificate = std::filesystem::path(RTWALL_TEST_DATA_DIR) / "web/test-cert.pem";
    EXPECT_THROW(checkWebSettings(w), InputError);  // no key
    w.key = std::filesystem::path(RTWALL_TEST_DATA_DIR) / "web/missing.pem";
    EXPECT_THROW(checkWebSettings(w), InputError);
    w.key = std::filesystem::path(RTWALL_TEST_DATA_DIR) / "web/test-key.pem";
    EXPECT_NO_THROW(checkWebSettings(w));
    // A port in use is one line too.
    testing::FakeConsole console(test::partsScene());
    WebApi api(console, kToken);
    WebSettings local;
    local.port = 0;
    WebServer first(api, local, [](const std::string&) {});
    local.port = first.port();
    EXPECT_THROW(WebServer(api, local, [](const std::string&) {}), InputError);
}

TEST(WebServer, ServesHttpsWithTheGivenCertificate) {
    testing::FakeConsole console(test::partsScene());
    WebApi api(console, kToken);
    WebSettings w;
    w.port = 0;
    w.certificate = std::filesystem::path(RTWALL_TEST_DATA_DIR) / "web/test-cert.pem";
    w.key = std::filesystem::path(RTWALL_TEST_DATA_DIR) / "web/test-key.pem";
    WebServer server(api, w, [](const std::string&) {});
    EXPECT_TRUE(server.url().starts_with("https://127.0.0.1:"));
    httplib::SSLClient tls("127.0.0.1", server.port());
    tls.enable_server_certificate_verification(false);  // self-signed
    tls.set_bearer_token_auth(kToken.c_str());
    auto r = tls.Get("/api/status");
    ASSERT_TRUE(r) << httplib::to_string(r.error());
    EXPECT_EQ(r->status, 200);
    EXPECT_EQ(json::parse(r->body)["frame"], 7);
    tls.set_bearer_token_auth("wrong-token-0123456789");
    r = tls.Get("/api/status");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 401);
    // Plain HTTP to the TLS port gets nothing.
    httplib::Client plain("127.0.0.1", server.port());
    plain.set_read_timeout(5, 0);
    plain.set_bearer_token_auth(kToken.c_str());
    r = plain.Get("/api/status");
    EXPECT_TRUE(!r || r->status != 200);
}

}  // namespace
}  // namespace rtwall
