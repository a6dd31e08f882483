// The master's side of a wall on several display nodes (issue 19), on loopback: a real Master,
// a scripted render client that acknowledges its tiles with TileDone (as a client does once it
// has sent them to the nodes) and scripted display nodes that report NodeHave and NodeSwapped.
// What is checked is the control: node list and tile masks reach the client, the frame ends on
// the last ack, the swap barrier releases a frame only when every node holds it, a stalled
// node is left out (and named) and rejoins. Every loop is bounded; every wait has a timeout.
#include "local_cluster.h"
#include "test_util.h"

#include "codec.h"
#include "net.h"
#include "protocol.h"
#include "security.h"

#include <rtwall/cluster.h>
#include <rtwall/denoise.h>
#include <rtwall/depth_codec.h>

#include <zmq.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <mutex>
#include <map>
#include <optional>
#include <thread>

namespace rtwall {
namespace {

using namespace cluster;
using Clock = std::chrono::steady_clock;

SceneDesc smallScene() { return test::quickDemo(64, 48, 16); }

// Render clients on threads of the test, joined when it ends. Declare it before the master so
// that the master goes first (its goodbye ends the clients), also when an assertion returns early.
class JoinedClients {
public:
    JoinedClients() = default;
    JoinedClients(const JoinedClients&) = delete;
    JoinedClients& operator=(const JoinedClients&) = delete;
    ~JoinedClients() {
        for (auto& t : threads_) t.join();
    }
    // `count` one-thread clients of `endpoint` (with the keys of `c`) that give up after `idleMs`
    // without their master.
    void start(const std::string& endpoint, int count, int idleMs, ClientSettings c = {}) {
        c.connect = endpoint;
        c.threads = 1;
        c.exitAfterIdleMs = idleMs;
        for (int i = 0; i < count; ++i) threads_.emplace_back([c] { runClient(c); });
    }

private:
    std::vector<std::thread> threads_;
};

// Node 0 ("left") shows x < 32, node 1 ("right") x >= 32: tiles are 16 wide, so none straddles.
std::vector<uint64_t> halves(int width, int height, int tileSize, const std::vector<FrameView>&) {
    std::vector<uint64_t> masks;
    for (const TileRect& t : makeTiles(width, height, tileSize)) masks.push_back(t.x0 < width / 2 ? 1u : 2u);
    return masks;
}

ClusterSettings nodeSettings() {
    ClusterSettings cs = test::inStep();
    cs.heartbeatMs = 50;
    cs.timeoutMs = 1500;
    cs.displayNodes.names = {"left", "right"};
    cs.displayNodes.wallText = "[wall]\n# two nodes\n";
    cs.displayNodes.routes = halves;
    cs.displayNodes.stallSeconds = 0.3;
    return cs;
}

double secondsNow() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

// One scripted peer on a DEALER: what it received, and how it answers.
class Peer {
public:
    // With `keys`, a CURVE client of the master whose public key is `serverKey`.
    Peer(zmq::context_t& ctx, const std::string& endpoint, const KeyPair* keys = nullptr, const std::string& serverKey = {})
        : socket_(ctx, zmq::socket_type::dealer) {
        socket_.set(zmq::sockopt::linger, 0);
        if (keys) {
            socket_.set(zmq::sockopt::curve_serverkey, serverKey);
            socket_.set(zmq::sockopt::curve_publickey, keys->publicKey);
            socket_.set(zmq::sockopt::curve_secretkey, keys->secretKey);
        }
        socket_.connect(endpoint);
    }
    virtual ~Peer() = default;
    void put(const std::vector<uint8_t>& bytes) { socket_.send(zmq::buffer(bytes), zmq::send_flags::dontwait); }
    template <class Msg> void putInSession(const Msg& m, uint32_t frame = 0) {
        Header h;
        h.session = session_;
        h.frame = frame;
        put(encodeMessage(h, m));
    }
    void pump() {
        for (int i = 0; i < 256; ++i) {
            zmq::message_t msg;
            if (!socket_.recv(msg, zmq::recv_flags::dontwait)) break;
            const auto* p = static_cast<const uint8_t*>(msg.data());
            const Header h = decodeHeader(p, msg.size());
            if (h.type == MsgType::Welcome || h.type == MsgType::NodeWelcome) session_ = h.session;
            on(h, p + kHeaderSize, msg.size() - kHeaderSize);
        }
        if (alive && Clock::now() - lastBeat_ > std::chrono::milliseconds(40)) {
            lastBeat_ = Clock::now();
            if (session_) putInSession(Heartbeat{});
        }
    }
    std::atomic<bool> alive{true};  // false: silent (a stalled or dead peer)

protected:
    virtual void on(const Header& h, const uint8_t* p, size_t n) = 0;
    zmq::socket_t socket_;
    uint64_t session_ = 0;
    Clock::time_point lastBeat_{};
};

// A client of the master that only reads the node lists it is sent: it never proves the state,
// so it is never given tiles (a FakeClient would acknowledge tiles that no node receives).
class ListReader : public Peer {
public:
    ListReader(zmq::context_t& ctx, const std::string& endpoint, const KeyPair* keys = nullptr, const std::string& serverKey = {})
        : ListReader(ctx, endpoint, keys, serverKey, "list-reader") {}
    std::mutex m;
    std::vector<NodeList> lists;

protected:
    ListReader(zmq::context_t& ctx, const std::string& endpoint, const KeyPair* keys, const std::string& serverKey,
               const std::string& name)
        : Peer(ctx, endpoint, keys, serverKey) {
        put(encodeMessage(Header{}, Hello{kProtocolVersion, 1, name}));
    }
    void on(const Header& h, const uint8_t* p, size_t n) override {
        std::lock_guard lock(m);
        if (h.type == MsgType::NodeList) lists.push_back(decodePayload<NodeList>(p, n));
    }
};

// A client of the master that proves the state, asks for tiles and acknowledges every tile it
// is given at once (no pixels); it keeps the node lists and tile routes it is sent.
class FakeClient : public ListReader {
public:
    FakeClient(zmq::context_t& ctx, const std::string& endpoint, const KeyPair* keys = nullptr, const std::string& serverKey = {})
        : ListReader(ctx, endpoint, keys, serverKey, "fake-client") {}
    std::vector<TileRoutes> routes;
    uint32_t acks = 0;

private:
    void on(const Header& h, const uint8_t* p, size_t n) override {
        std::lock_guard lock(m);
        switch (h.type) {
        case MsgType::SceneSnapshot: {
            const SceneSnapshot snap = decodePayload<SceneSnapshot>(p, n);
            putInSession(Ready{snap.updateSeq, stateHash(snap)});
            break;
        }
        case MsgType::NodeList: lists.push_back(decodePayload<NodeList>(p, n)); break;
        case MsgType::TileRoutes: routes.push_back(decodePayload<TileRoutes>(p, n)); break;
        case MsgType::FrameBegin: {
            const FrameBegin fb = decodePayload<FrameBegin>(p, n);
            putInSession(TileRequest{fb.frame, 64}, fb.frame);
            break;
        }
        case MsgType::TileAssign: {
            const TileAssign a = decodePayload<TileAssign>(p, n);
            for (uint32_t t : a.tiles) {
                putInSession(TileDone{a.frame, t, 100, 1000}, a.frame);
                ++acks;
            }
            break;
        }
        default: break;
        }
    }
};

class FakeNode : public Peer {
public:
    // With `takeTiles`, the node binds a ROUTER on loopback for the clients' tiles and keeps what
    // arrives (TileResults by frame and tile).
    FakeNode(zmq::context_t& ctx, const std::string& endpoint, const std::string& name, bool takeTiles = false,
             const KeyPair* keys = nullptr, const std::string& serverKey = {})
        : Peer(ctx, endpoint, keys, serverKey) {
        std::string tileEndpoint = "tcp://127.0.0.1:9";
        if (takeTiles) {
            tiles_.emplace(ctx, zmq::socket_type::router);
            tiles_->set(zmq::sockopt::linger, 0);
            tiles_->bind("tcp://127.0.0.1:0");
            tileEndpoint = tiles_->get(zmq::sockopt::last_endpoint);
        }
        put(encodeMessage(Header{}, NodeHello{kProtocolVersion, name, tileEndpoint, ""}));
    }
    std::map<std::pair<uint32_t, uint32_t>, TileResult> received;  // by (frame, tile)
    uint64_t repeats = 0;

    void pumpTiles() {
        if (!tiles_) return;
        for (int i = 0; i < 256; ++i) {
            zmq::message_t identity, msg;
            if (!tiles_->recv(identity, zmq::recv_flags::dontwait)) break;
            if (!tiles_->recv(msg, zmq::recv_flags::dontwait)) break;
            const auto* p = static_cast<const uint8_t*>(msg.data());
            const Header h = decodeHeader(p, msg.size());
            if (h.type != MsgType::TileResult) continue;
            TileResult r = decodePayload<TileResult>(p + kHeaderSize, msg.size() - kHeaderSize);
            std::lock_guard lock(m);
            if (!received.emplace(std::make_pair(r.frame, r.tile), r).second) ++repeats;
        }
    }
    struct Swap {
        uint32_t frame;
        std::vector<std::string> leftOut;
        double at;
    };
    std::mutex m;
    std::optional<uint32_t> index;
    std::optional<std::string> goodbye;
    std::vector<TileRoutes> routes;
    std::vector<NodeFrame> frames;
    std::vector<double> frameAt;  // when each of `frames` came
    std::vector<Swap> swaps;
    std::vector<double> haveSentAt;  // per NodeHave sent
    double haveDelay = 0;            // seconds between NodeFrame and NodeHave (a slow node)

    void flushDelayed() {
        std::lock_guard lock(m);
        for (auto it = delayed_.begin(); it != delayed_.end();) {
            if (secondsNow() < it->second) {
                ++it;
                continue;
            }
            if (alive) {
                haveSentAt.push_back(secondsNow());
                putInSession(NodeHave{it->first}, it->first);
            }
            it = delayed_.erase(it);
        }
    }

private:
    void on(const Header& h, const uint8_t* p, size_t n) override {
        std::lock_guard lock(m);
        switch (h.type) {
        case MsgType::NodeWelcome:
            index = decodePayload<NodeWelcome>(p, n).node;
            if (alive) putInSession(Heartbeat{});  // it answers at once, as runDisplayNode does: the clients learn of it then
            break;
        case MsgType::Goodbye: goodbye = decodePayload<Goodbye>(p, n).reason; break;
        case MsgType::TileRoutes: routes.push_back(decodePayload<TileRoutes>(p, n)); break;
        case MsgType::NodeFrame: {
            const NodeFrame f = decodePayload<NodeFrame>(p, n);
            frames.push_back(f);
            frameAt.push_back(secondsNow());
            delayed_.emplace_back(f.frame, secondsNow() + haveDelay);
            break;
        }
        case MsgType::NodeSwap: {
            const NodeSwap s = decodePayload<NodeSwap>(p, n);
            swaps.push_back({s.frame, s.leftOut, secondsNow()});
            if (alive) putInSession(NodeSwapped{s.frame}, s.frame);
            break;
        }
        default: break;
        }
    }
    std::vector<std::pair<uint32_t, double>> delayed_;
    std::optional<zmq::socket_t> tiles_;
};

// The scripted peers on one thread, pumped until the object goes.
class Peers {
public:
    explicit Peers(std::vector<Peer*> peers) : peers_(std::move(peers)) {
        thread_ = std::thread([this] {
            while (!stop_) {
                {
                    std::lock_guard lock(mutex_);
                    for (Peer* p : peers_) {
                        p->pump();
                        if (auto* node = dynamic_cast<FakeNode*>(p)) {
                            node->flushDelayed();
                            node->pumpTiles();
                        }
                    }
                }
                std::this_thread::sleep_for(std::chrono::milliseconds(1));
            }
        });
    }
    void add(Peer* p) {
        std::lock_guard lock(mutex_);
        peers_.push_back(p);
    }
    void remove(Peer* p) {
        std::lock_guard lock(mutex_);
        std::erase(peers_, p);
    }
    ~Peers() {
        stop_ = true;
        thread_.join();
    }

private:
    std::mutex mutex_;
    std::vector<Peer*> peers_;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

// Waits (at most 5 s) until pred() holds under the peer's lock.
template <class P, class F> bool waitFor(P& peer, F pred) {
    const auto end = Clock::now() + std::chrono::seconds(5);
    while (Clock::now() < end) {
        {
            std::lock_guard lock(peer.m);
            if (pred()) return true;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
}

struct Wall {
    SceneDesc scene = smallScene();
    Master master{scene, nodeSettings()};
    zmq::context_t ctx{1};
    FakeNode left{ctx, master.endpoint(), "left"};
    FakeNode right{ctx, master.endpoint(), "right"};
    FakeClient client{ctx, master.endpoint()};
    Peers peers{{&left, &right, &client}};
};

TEST(DisplayNodes, ClientsGetNodesAndMasksAndTheFrameEndsOnTheLastAck) {
    Wall w;
    ASSERT_TRUE(waitFor(w.left, [&] { return w.left.index.has_value(); }));
    ASSERT_TRUE(waitFor(w.right, [&] { return w.right.index.has_value(); }));
    EXPECT_EQ(*w.left.index, 0u);
    EXPECT_EQ(*w.right.index, 1u);
    ASSERT_TRUE(w.master.waitForClients(1, 5000));

    FrameReport report;
    const Image image = w.master.renderFrame(&report);
    EXPECT_TRUE(image.rgb.empty());  // the pixels are the nodes'
    EXPECT_EQ(report.displayNodes, 2u);
    // 12 tiles, each acknowledged with 1000 bytes sent to its one node.
    EXPECT_EQ(report.bytes, 12u * 1000u);
    EXPECT_EQ(report.counters.unexpected, 0u);

    const std::vector<uint64_t> expected = halves(64, 48, 16, {});
    {
        std::lock_guard lock(w.client.m);
        EXPECT_EQ(w.client.acks, 12u);
        ASSERT_EQ(w.client.routes.size(), 1u);
        EXPECT_EQ(w.client.routes[0].masks, expected);
        ASSERT_FALSE(w.client.lists.empty());
        const NodeList& last = w.client.lists.back();
        ASSERT_EQ(last.nodes.size(), 2u);
        EXPECT_EQ(last.nodes[0].name, "left");
        EXPECT_EQ(last.nodes[0].endpoint, "tcp://127.0.0.1:9");
        EXPECT_EQ(last.nodes[1].name, "right");
    }
    // A second frame of the same size: the masks are not sent again.
    w.master.renderFrame(&report);
    {
        std::lock_guard lock(w.client.m);
        EXPECT_EQ(w.client.routes.size(), 1u);
        EXPECT_EQ(w.client.acks, 24u);
    }
    for (FakeNode* node : {&w.left, &w.right}) {
        ASSERT_TRUE(waitFor(*node, [&] { return node->swaps.size() >= 2; }));
        std::lock_guard lock(node->m);
        EXPECT_EQ(node->routes.size(), 1u);
        ASSERT_EQ(node->frames.size(), 2u);
        EXPECT_EQ(node->frames[0].width, 64);
        EXPECT_EQ(node->frames[0].tileSize, 16);
        EXPECT_EQ(node->swaps[0].frame, node->frames[0].frame);
        EXPECT_EQ(node->swaps[1].frame, node->frames[1].frame);
        EXPECT_TRUE(node->swaps[0].leftOut.empty());
    }
}

TEST(DisplayNodes, NoNodeSwapsBeforeTheSlowestHoldsTheFrame) {
    Wall w;
    {
        std::lock_guard lock(w.right.m);
        w.right.haveDelay = 0.15;  // well under the stall time (0.3 s): it is waited for
    }
    ASSERT_TRUE(waitFor(w.right, [&] { return w.right.index.has_value(); }));
    ASSERT_TRUE(waitFor(w.left, [&] { return w.left.index.has_value(); }));
    ASSERT_TRUE(w.master.waitForClients(1, 5000));
    for (int i = 0; i < 3; ++i) w.master.renderFrame();
    ASSERT_TRUE(waitFor(w.left, [&] { return w.left.swaps.size() >= 3; }));
    ASSERT_TRUE(waitFor(w.right, [&] { return w.right.swaps.size() >= 3; }));
    std::scoped_lock lock(w.left.m, w.right.m);
    ASSERT_GE(w.right.haveSentAt.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        // The swap of frame i reached the fast node only after the slow one said it held it.
        EXPECT_GE(w.left.swaps[i].at, w.right.haveSentAt[i]) << "frame " << w.left.swaps[i].frame;
        EXPECT_TRUE(w.left.swaps[i].leftOut.empty());
    }
}

// Master::waitForSwap (what paces `rtwall bench cluster --display-nodes`): it returns when the
// barrier has released the frame, which is after the slow node said it holds it, and gives up
// on a frame that was never rendered.
TEST(DisplayNodes, WaitForSwapReturnsOnlyOnceTheSlowestNodeHoldsTheFrame) {
    Wall w;
    {
        std::lock_guard lock(w.right.m);
        w.right.haveDelay = 0.1;
    }
    ASSERT_TRUE(waitFor(w.right, [&] { return w.right.index.has_value(); }));
    ASSERT_TRUE(waitFor(w.left, [&] { return w.left.index.has_value(); }));
    ASSERT_TRUE(w.master.waitForClients(1, 5000));
    for (int i = 0; i < 2; ++i) {
        FrameReport report;
        w.master.renderFrame(&report);
        ASSERT_TRUE(w.master.waitForSwap(report.frame, 5000)) << "frame " << report.frame;
        const double released = secondsNow();
        std::lock_guard lock(w.right.m);
        ASSERT_EQ(w.right.haveSentAt.size(), size_t(i + 1));
        EXPECT_LE(w.right.haveSentAt.back(), released);
    }
    const auto t0 = Clock::now();
    EXPECT_FALSE(w.master.waitForSwap(100, 200));  // never begun
    EXPECT_GE(Clock::now() - t0, std::chrono::milliseconds(200));
}

// A denoising node's history is the frame before, and it holds two frames: with a denoise
// mode set, the master begins frame N only once frame N-2 was swapped, whatever the caller does
// (here: frames as fast as a fake client acknowledges, a node 0.15 s slow). Without one the
// frames run ahead of the swaps (what shows the check can fail).
TEST(DisplayNodes, WhileNodesDenoiseAFrameBeginsOnlyAfterTheSwapOfTheOneTwoBefore) {
    for (const bool denoise : {true, false}) {
        SCOPED_TRACE(denoise ? "denoising" : "not denoising");
        Wall w;
        {
            std::lock_guard lock(w.right.m);
            w.right.haveDelay = 0.15;
        }
        ASSERT_TRUE(waitFor(w.right, [&] { return w.right.index.has_value(); }));
        ASSERT_TRUE(waitFor(w.left, [&] { return w.left.index.has_value(); }));
        ASSERT_TRUE(w.master.waitForClients(1, 5000));
        ASSERT_TRUE(w.master.waitForDisplayNodes(5000));
        DenoiseSettings d;
        d.mode = denoise ? DenoiseSettings::Mode::Svgf : DenoiseSettings::Mode::Off;
        w.master.setDenoise(d, 8);
        FrameReport report;
        for (int i = 0; i < 5; ++i) w.master.renderFrame(&report);
        ASSERT_TRUE(w.master.waitForSwap(report.frame, 5000));
        std::lock_guard lock(w.left.m);
        ASSERT_EQ(w.left.frames.size(), 5u);
        size_t ahead = 0;
        for (size_t i = 2; i < w.left.frames.size(); ++i) {
            const uint32_t twoBefore = w.left.frames[i].frame - 2;
            const auto swap = std::find_if(w.left.swaps.begin(), w.left.swaps.end(),
                                           [&](const FakeNode::Swap& s) { return s.frame == twoBefore; });
            ahead += swap == w.left.swaps.end() || swap->at > w.left.frameAt[i];
        }
        if (denoise) EXPECT_EQ(ahead, 0u) << "frames begun before the swap of the one two before";
        else EXPECT_EQ(ahead, 3u) << "without denoising the frames need not wait";
    }
}

TEST(DisplayNodes, AStalledNodeIsLeftOutAndNamedThenRejoins) {
    Wall w;
    ASSERT_TRUE(waitFor(w.left, [&] { return w.left.index.has_value(); }));
    ASSERT_TRUE(waitFor(w.right, [&] { return w.right.index.has_value(); }));
    ASSERT_TRUE(w.master.waitForClients(1, 5000));
    w.master.renderFrame();
    ASSERT_TRUE(waitFor(w.left, [&] { return w.left.swaps.size() >= 1; }));

    w.right.alive = false;  // stalls: no NodeHave, no heartbeat
    FrameReport report;
    for (int i = 0; i < 2; ++i) w.master.renderFrame(&report);  // the frames end on the client's acks regardless
    // Once the stall time has passed, the newest frame goes to the left node alone (an older one
    // that waited is superseded), with the right node named.
    ASSERT_TRUE(waitFor(w.left, [&] { return w.left.swaps.back().frame == report.frame; }));
    {
        std::lock_guard lock(w.left.m);
        EXPECT_EQ(w.left.swaps.back().leftOut, std::vector<std::string>{"right"});
    }
    // After the timeout it is gone from the clients' node list.
    ASSERT_TRUE(waitFor(w.client, [&] { return !w.client.lists.empty() && w.client.lists.back().nodes.size() == 1; }));

    // It comes back on a new connection (a restarted node) and takes part again.
    w.peers.remove(&w.right);
    FakeNode again(w.ctx, w.master.endpoint(), "right");
    w.peers.add(&again);
    ASSERT_TRUE(waitFor(again, [&] { return again.index.has_value(); }));
    EXPECT_EQ(*again.index, 1u);
    ASSERT_TRUE(waitFor(w.client, [&] { return w.client.lists.back().nodes.size() == 2; }));
    w.master.renderFrame();
    ASSERT_TRUE(waitFor(again, [&] { return !again.swaps.empty(); }));
    {
        std::lock_guard lock(again.m);
        EXPECT_TRUE(again.swaps.back().leftOut.empty());
        // It was sent the masks before its first frame.
        ASSERT_EQ(again.routes.size(), 1u);
        EXPECT_EQ(again.routes[0].masks, halves(64, 48, 16, {}));
    }
    w.peers.remove(&again);
}

// Real render clients (runClient threads): each tile goes to exactly the nodes of its mask, with
// the pixels one machine renders, and the master gets only acks.
TEST(DisplayNodes, RenderClientsSendEachTileToItsNodesBitIdentical) {
    const SceneDesc scene = smallScene();
    JoinedClients clients;
    zmq::context_t ctx{1};
    auto owned = std::make_unique<Master>(scene, nodeSettings());
    Master& master = *owned;
    FakeNode left(ctx, master.endpoint(), "left", true), right(ctx, master.endpoint(), "right", true);
    Peers peers({&left, &right});
    ASSERT_TRUE(waitFor(left, [&] { return left.index.has_value(); }));
    ASSERT_TRUE(waitFor(right, [&] { return right.index.has_value(); }));
    clients.start(master.endpoint(), 2, 3000);  // never outlive the test by much
    ASSERT_TRUE(master.waitForClients(2, 10000));

    // A frame whose tiles never reach the nodes (or whose acks never come) would not end: it
    // is given 20 s, then cancelled (Master::setStopFlag) and the test fails.
    std::atomic<bool> stop{false}, done{false};
    master.setStopFlag(&stop);
    std::thread watchdog([&] {
        for (int i = 0; i < 2000 && !done; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
        stop = !done;
    });
    FrameReport report;
    bool finished = false;
    try {
        master.renderFrame(&report);
        finished = true;
    } catch (const Cancelled&) {
    }
    done = true;
    watchdog.join();
    ASSERT_TRUE(finished) << "the frame did not end within 20 s";
    EXPECT_EQ(report.counters.unexpected, 0u) << describeCounters(report.counters);
    const std::vector<uint64_t> masks = halves(64, 48, 16, {});
    const std::vector<TileRect> rects = makeTiles(64, 48, 16);
    const Scene reference(scene);
    const Image one = renderFrame(reference, Camera(scene.cameras.front(), 64, 48), scene.settings);
    for (FakeNode* node : {&left, &right}) {
        const uint64_t bit = node == &left ? 1 : 2;
        size_t routed = 0;
        for (uint64_t mask : masks) routed += (mask & bit) ? 1 : 0;
        ASSERT_TRUE(waitFor(*node, [&] {
            size_t n = 0;
            for (const auto& [key, r] : node->received) n += key.first == report.frame ? 1 : 0;
            return n >= routed;
        })) << "node " << bit;
        std::lock_guard lock(node->m);
        EXPECT_EQ(node->repeats, 0u);
        for (const auto& [key, r] : node->received) {
            if (key.first != report.frame) continue;
            ASSERT_LT(r.tile, masks.size());
            EXPECT_TRUE(masks[r.tile] & bit) << "tile " << r.tile << " went to a node that does not show it";
            const TileRect& t = rects[r.tile];
            std::vector<uint8_t> pixels(size_t(t.width()) * t.height() * 3);
            decodeTile(r.codec, r.pixels.data(), r.pixels.size(), t.width(), t.height(), pixels.data(), size_t(t.width()) * 3);
            for (int y = 0; y < t.height(); ++y)
                ASSERT_EQ(0, std::memcmp(pixels.data() + size_t(y) * t.width() * 3,
                                         one.rgb.data() + (size_t(t.y0 + y) * 64 + size_t(t.x0)) * 3, size_t(t.width()) * 3))
                    << "tile " << r.tile << " row " << y;
        }
    }
    // The nodes held the frame and were told to swap it.
    ASSERT_TRUE(waitFor(left, [&] { return !left.swaps.empty() && left.swaps.back().frame == report.frame; }));
    ASSERT_TRUE(waitFor(right, [&] { return !right.swaps.empty() && right.swaps.back().frame == report.frame; }));
}

// runDisplayNode on a thread: what it was given to present.
struct NodeThread {
    struct Shown {
        uint32_t frame;
        std::optional<Image> image;  // the mono image or the left eye's
        std::optional<Image> right;
        std::vector<std::string> leftOut;
    };
    NodeThread(const std::string& endpoint, const std::string& name, const std::function<void(DisplayNodeRun&)>& configure = {}) {
        run.connect = endpoint;
        run.name = name;
        run.exitAfterIdleMs = 5000;
        run.stop = &stop;
        run.counters = counters;
        if (configure) configure(run);
        run.onWall = [this](const std::string& text) {
            std::lock_guard lock(m);
            wall = text;
        };
        run.present = [this](uint32_t frame, const Image* left, const Image* right, const std::vector<std::string>& leftOut) {
            std::lock_guard lock(m);
            shown.push_back({frame, left ? std::optional<Image>(*left) : std::nullopt,
                             right ? std::optional<Image>(*right) : std::nullopt, leftOut});
        };
        run.depth = [this](uint32_t frame, const std::vector<std::vector<float>>& views) {
            std::lock_guard lock(m);
            depths.emplace_back(frame, views);
        };
        thread = std::thread([this] {
            status = runDisplayNode(run);
            finished = true;
        });
    }
    ~NodeThread() {
        stop = true;
        thread.join();
    }
    std::mutex m;
    std::string wall;
    std::vector<Shown> shown;
    std::vector<std::pair<uint32_t, std::vector<std::vector<float>>>> depths;  // per frame with depth: each view's
    std::atomic<bool> stop{false}, finished{false};
    std::atomic<int> status{-1};
    std::shared_ptr<DisplayNodeCounters> counters = std::make_shared<DisplayNodeCounters>();
    DisplayNodeRun run;
    std::thread thread;
};

// Two display-node processes' network side (runDisplayNode) with real render clients: each
// node presents the frame with exactly its tiles, bit-identical to one machine; killed, the other
// goes on and names it; restarted, it takes part again.
TEST(DisplayNodes, NodesPresentTheirTilesAndSurviveAKilledNode) {
    const SceneDesc scene = smallScene();
    JoinedClients clients;
    ClusterSettings cs = nodeSettings();
    cs.timeoutMs = 1000;
    auto owned = std::make_unique<Master>(scene, cs);
    Master& master = *owned;
    auto left = std::make_unique<NodeThread>(master.endpoint(), "left");
    auto right = std::make_unique<NodeThread>(master.endpoint(), "right");
    clients.start(master.endpoint(), 2, 3000);
    ASSERT_TRUE(master.waitForClients(2, 10000));
    ASSERT_TRUE(waitFor(*left, [&] { return !left->wall.empty(); }));
    ASSERT_TRUE(waitFor(*right, [&] { return !right->wall.empty(); }));
    EXPECT_EQ(left->wall, cs.displayNodes.wallText);

    FrameReport report;
    master.renderFrame(&report);
    const Scene reference(scene);
    const Image one = renderFrame(reference, Camera(scene.cameras.front(), 64, 48), scene.settings);
    const std::vector<uint64_t> masks = halves(64, 48, 16, {});
    const std::vector<TileRect> rects = makeTiles(64, 48, 16);
    for (NodeThread* node : {left.get(), right.get()}) {
        const uint64_t bit = node == left.get() ? 1 : 2;
        ASSERT_TRUE(waitFor(*node, [&] { return !node->shown.empty() && node->shown.back().frame == report.frame; }));
        std::lock_guard lock(node->m);
        const NodeThread::Shown& s = node->shown.back();
        ASSERT_TRUE(s.image.has_value()) << "node " << bit << " did not hold the frame it was told to swap";
        EXPECT_TRUE(s.leftOut.empty());
        ASSERT_EQ(s.image->width, 64);
        for (size_t t = 0; t < rects.size(); ++t) {
            if (!(masks[t] & bit)) continue;
            const TileRect& r = rects[t];
            for (int y = r.y0; y < r.y1; ++y)
                ASSERT_EQ(0, std::memcmp(s.image->rgb.data() + (size_t(y) * 64 + size_t(r.x0)) * 3,
                                         one.rgb.data() + (size_t(y) * 64 + size_t(r.x0)) * 3, size_t(r.width()) * 3))
                    << "node " << bit << " tile " << t << " row " << y;
        }
    }

    // The right node dies: frames go on, and the left node's swaps name it.
    right.reset();
    for (int i = 0; i < 3; ++i) master.renderFrame(&report);
    ASSERT_TRUE(waitFor(*left, [&] {
        return !left->shown.empty() && left->shown.back().frame == report.frame;
    }));
    {
        std::lock_guard lock(left->m);
        bool named = false;
        for (const auto& s : left->shown) named = named || s.leftOut == std::vector<std::string>{"right"};
        EXPECT_TRUE(named) << "no swap named the dead node";
        EXPECT_TRUE(left->shown.back().image.has_value());
    }
    // Restarted, it joins again and presents the next frames with the rest.
    right = std::make_unique<NodeThread>(master.endpoint(), "right");
    ASSERT_TRUE(waitFor(*right, [&] { return !right->wall.empty(); }));
    bool together = false;
    for (int i = 0; i < 20 && !together; ++i) {
        master.renderFrame(&report);
        together = waitFor(*right, [&] {
            return !right->shown.empty() && right->shown.back().frame == report.frame && right->shown.back().image &&
                   right->shown.back().leftOut.empty();
        });
    }
    EXPECT_TRUE(together) << "the restarted node never presented a frame with the others";
    right.reset();
    left.reset();
}

// Views and accumulation on display nodes (protocol 12) ---------------------------------------

CameraDesc eyeCamera(const SceneDesc& d, float dx) {
    CameraDesc c = d.cameras.front();
    c.position.x += dx;
    c.lookAt.x += dx;
    return c;
}

// Each view's tiles split like halves(): view by view, the left half to node 0, the right to 1.
std::vector<uint64_t> viewHalves(int width, int height, int tileSize, const std::vector<FrameView>& views) {
    if (views.empty()) return halves(width, height, tileSize, views);
    std::vector<uint64_t> masks;
    for (const ViewTile& t : viewTiles(views, width, height, tileSize)) masks.push_back(t.rect.x0 < width / 2 ? 1u : 2u);
    return masks;
}

// Whether `image` equals `expected` on the half of the 64-pixel-wide frame node `bit` shows.
::testing::AssertionResult sameOnNode(const Image& image, const Image& expected, uint64_t bit) {
    if (image.width != expected.width || image.height != expected.height)
        return ::testing::AssertionFailure() << "size " << image.width << "x" << image.height << ", expected "
                                             << expected.width << "x" << expected.height;
    const int x0 = bit == 1 ? 0 : image.width / 2, x1 = bit == 1 ? image.width / 2 : image.width;
    for (int y = 0; y < image.height; ++y)
        if (std::memcmp(image.pixel(x0, y), expected.pixel(x0, y), size_t(x1 - x0) * 3) != 0)
            return ::testing::AssertionFailure() << "row " << y << " differs";
    return ::testing::AssertionSuccess();
}

// A master with render-client threads and two runDisplayNode threads, both joined.
struct NodeWall {
    JoinedClients clients;  // joined after the master is gone (its goodbye ends them)
    std::unique_ptr<Master> master;
    std::unique_ptr<NodeThread> left, right;

    NodeWall(const SceneDesc& scene, ClusterSettings cs) {
        master = std::make_unique<Master>(scene, cs);
        left = std::make_unique<NodeThread>(master->endpoint(), "left");
        right = std::make_unique<NodeThread>(master->endpoint(), "right");
        clients.start(master->endpoint(), 2, 5000);
    }
    bool ready() {
        return master->waitForClients(2, 20000) && waitFor(*left, [&] { return !left->wall.empty(); }) &&
               waitFor(*right, [&] { return !right->wall.empty(); });
    }
    // What `node` presented of `frame` (waits for it, at most 5 s).
    std::optional<NodeThread::Shown> shownOf(NodeThread& node, uint32_t frame) {
        std::optional<NodeThread::Shown> out;
        waitFor(node, [&] {
            for (const auto& s : node.shown)
                if (s.frame == frame) out = s;
            return out.has_value();
        });
        return out;
    }
    ~NodeWall() {
        left.reset();
        right.reset();
        master.reset();
    }
};

// A stereo frame (both eyes in one pass) on two nodes: each node presents a left and a right
// image whose pixels on its half are one machine's render of that eye, bit for bit.
TEST(DisplayNodes, StereoFramesShowBothEyesBitIdentical) {
    const SceneDesc scene = smallScene();
    ClusterSettings cs = nodeSettings();
    cs.displayNodes.routes = viewHalves;
    cs.displayNodes.viewEyes = {0, 1};
    NodeWall w(scene, cs);
    ASSERT_TRUE(w.ready());
    const std::vector<FrameView> views{{eyeCamera(scene, -0.2f), {}, 0, 0}, {eyeCamera(scene, 0.2f), {}, 0, 0}};
    w.master->setViews(views);
    FrameReport report;
    w.master->renderViews(&report);
    ASSERT_EQ(report.views, 2u);
    const Scene reference(scene);
    const Image leftEye = renderFrame(reference, Camera(views[0].camera, 64, 48), scene.settings);
    const Image rightEye = renderFrame(reference, Camera(views[1].camera, 64, 48), scene.settings);
    ASSERT_NE(leftEye.rgb, rightEye.rgb);
    for (NodeThread* node : {w.left.get(), w.right.get()}) {
        const uint64_t bit = node == w.left.get() ? 1 : 2;
        const auto shown = w.shownOf(*node, report.frame);
        ASSERT_TRUE(shown.has_value()) << "node " << bit;
        ASSERT_TRUE(shown->image.has_value()) << "node " << bit;
        ASSERT_TRUE(shown->right.has_value()) << "node " << bit << " presented no right eye";
        EXPECT_TRUE(sameOnNode(*shown->image, leftEye, bit)) << "node " << bit << ", left eye";
        EXPECT_TRUE(sameOnNode(*shown->right, rightEye, bit)) << "node " << bit << ", right eye";
    }
}

// Issue 27: with depth, each node keeps each view's depth of the frames it shows: one machine's
// depth through the depth code on the node's tiles, NaN (a hole) on the other node's. Without,
// nothing is handed over.
TEST(DisplayNodes, NodesKeepTheirTilesDepthPerView) {
    const SceneDesc scene = smallScene();
    ClusterSettings cs = nodeSettings();
    cs.depth = true;
    NodeWall w(scene, cs);
    ASSERT_TRUE(w.ready());
    FrameReport report;
    w.master->renderFrame(&report);
    ASSERT_TRUE(report.depth);
    const RenderedFrame one = renderFrameWithDepth(Scene(scene), Camera(scene.cameras.front(), 64, 48), scene.settings,
                                                   report.frame);
    for (NodeThread* node : {w.left.get(), w.right.get()}) {
        const bool isLeft = node == w.left.get();
        ASSERT_TRUE(w.shownOf(*node, report.frame).has_value());
        std::vector<std::vector<float>> views;
        {
            std::lock_guard lock(node->m);
            for (const auto& [frame, d] : node->depths)
                if (frame == report.frame) views = d;
        }
        ASSERT_EQ(views.size(), 1u) << (isLeft ? "left" : "right");
        ASSERT_EQ(views[0].size(), size_t(64 * 48));
        size_t wrong = 0;
        for (int y = 0; y < 48; ++y)
            for (int x = 0; x < 64; ++x) {
                const size_t i = size_t(y) * 64 + size_t(x);
                const bool mine = (x < 32) == isLeft;
                const float got = views[0][i];
                wrong += mine ? got != decodeDepth(encodeDepth(one.depth[i])) : !std::isnan(got);
            }
        EXPECT_EQ(wrong, 0u) << (isLeft ? "left" : "right");
    }
}

// A CAVE-like frame: two planes of one (mono) eye, each view with its region of the image: the
// node's one image takes each plane's pixels from its view.
TEST(DisplayNodes, PlanesAreComposedIntoTheEyeImageBitIdentical) {
    const SceneDesc scene = smallScene();
    ClusterSettings cs = nodeSettings();
    cs.displayNodes.routes = viewHalves;
    cs.displayNodes.viewEyes = {-1, -1};
    NodeWall w(scene, cs);
    ASSERT_TRUE(w.ready());
    // Plane 0 shows x < 32 (node left), plane 1 the rest; a 64x48 reference image.
    const std::vector<FrameView> views{{eyeCamera(scene, -0.3f), {{0, 0, 32, 48}}, 64, 48},
                                       {eyeCamera(scene, 0.3f), {{32, 0, 32, 48}}, 64, 48}};
    w.master->setViews(views);
    FrameReport report;
    w.master->renderViews(&report);
    const Scene reference(scene);
    const Image plane0 = renderFrame(reference, Camera(views[0].camera, 64, 48), scene.settings);
    const Image plane1 = renderFrame(reference, Camera(views[1].camera, 64, 48), scene.settings);
    const auto left = w.shownOf(*w.left, report.frame), right = w.shownOf(*w.right, report.frame);
    ASSERT_TRUE(left && left->image && right && right->image);
    EXPECT_FALSE(left->right.has_value());  // mono: one image
    EXPECT_TRUE(sameOnNode(*left->image, plane0, 1));
    EXPECT_TRUE(sameOnNode(*right->image, plane1, 2));
}

// A still view of a stochastic (GI) scene: after K frames each node shows one machine's running
// mean of those K frame numbers (linear half-float tiles, Accumulator::addLinear), bit for bit;
// a scene change restarts it. Mono, and stereo with one running mean per view.
class NodeAccumulation : public ::testing::TestWithParam<bool> {};

TEST_P(NodeAccumulation, AStillViewAccumulatesAsOnOneMachine) {
    const bool stereo = GetParam();
    SceneDesc scene = smallScene();
    scene.settings.gi = true;
    ASSERT_TRUE(rendersStochastically(scene));
    ClusterSettings cs = nodeSettings();
    cs.displayNodes.routes = viewHalves;
    if (stereo) cs.displayNodes.viewEyes = {0, 1};
    NodeWall w(scene, cs);
    ASSERT_TRUE(w.ready());
    std::vector<FrameView> views;
    if (stereo) views = {{eyeCamera(scene, -0.2f), {}, 0, 0}, {eyeCamera(scene, 0.2f), {}, 0, 0}};
    w.master->setViews(views);
    const std::vector<CameraDesc> cameras = stereo ? std::vector<CameraDesc>{views[0].camera, views[1].camera}
                                                   : std::vector<CameraDesc>{scene.cameras.front()};
    const Scene reference(scene);
    std::vector<Accumulator> sums(cameras.size());
    auto check = [&](const char* when) {
        FrameReport report;
        w.master->renderViews(&report);
        ASSERT_TRUE(report.stochastic);
        ASSERT_TRUE(report.linear);
        std::vector<Image> expected;
        for (size_t v = 0; v < cameras.size(); ++v) {
            const std::vector<float> one = renderFrameLinear(reference, Camera(cameras[v], 64, 48), scene.settings, report.frame);
            sums[v].addLinear(one.data(), 64, 48);
            expected.push_back(sums[v].resolve());
        }
        for (NodeThread* node : {w.left.get(), w.right.get()}) {
            const uint64_t bit = node == w.left.get() ? 1 : 2;
            const auto shown = w.shownOf(*node, report.frame);
            ASSERT_TRUE(shown && shown->image) << when << ": node " << bit << " did not present frame " << report.frame;
            EXPECT_TRUE(sameOnNode(*shown->image, expected[0], bit)) << when << ": node " << bit << ", frame " << report.frame;
            if (stereo) {
                ASSERT_TRUE(shown->right.has_value());
                EXPECT_TRUE(sameOnNode(*shown->right, expected[1], bit)) << when << ": node " << bit << ", right eye";
            }
        }
    };
    for (int k = 0; k < 3; ++k) check("still view");
    ASSERT_EQ(sums[0].frames(), 3);
    // A scene change (the light) restarts every running mean, on one machine and on the nodes.
    Light light = scene.lights.front();
    light.intensity *= 0.5f;
    w.master->setLight(0, light);
    scene.lights.front() = light;
    const Scene changed(scene);
    for (Accumulator& a : sums) a.reset();
    {
        FrameReport report;
        w.master->renderViews(&report);
        for (size_t v = 0; v < cameras.size(); ++v) {
            const std::vector<float> one = renderFrameLinear(changed, Camera(cameras[v], 64, 48), scene.settings, report.frame);
            sums[v].addLinear(one.data(), 64, 48);
        }
        const Image expected = sums[0].resolve();
        for (NodeThread* node : {w.left.get(), w.right.get()}) {
            const uint64_t bit = node == w.left.get() ? 1 : 2;
            const auto shown = w.shownOf(*node, report.frame);
            ASSERT_TRUE(shown && shown->image);
            EXPECT_TRUE(sameOnNode(*shown->image, expected, bit)) << "after the change: node " << bit;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(MonoAndStereo, NodeAccumulation, ::testing::Bool(),
                         [](const auto& p) { return p.param ? "Stereo" : "Mono"; });

// CURVE on the node links ----------------------------------------------------------------------

// Waits (at most 10 s) for `pred`.
template <class F> bool eventually(F pred) {
    const auto end = Clock::now() + std::chrono::seconds(10);
    while (Clock::now() < end) {
        if (pred()) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return pred();
}

// Every link keyed with exactly the arguments a master gives the processes it starts on its PC
// (localClientArgs: --key, --server-key): nodes join, clients send them tiles over CURVE, the
// screens are bit-identical; a stranger's key is refused by a node's tile socket, said on both
// sides, and the wall goes on.
TEST(DisplayNodes, CurveKeysOnEveryNodeLinkFramesBitIdenticalAndStrangersRefused) {
    const SceneDesc scene = smallScene();
    const auto dir = test::scratchDir();
    writeNewKeyPair(dir / "master");
    ClusterSettings cs = nodeSettings();
    cs.keyFile = dir / "master.key";
    cs.localClients = 2;  // the master makes a key pair for its PC's processes
    JoinedClients clients;
    auto owned = std::make_unique<Master>(scene, cs);
    Master& master = *owned;
    const std::vector<std::string> args = master.localClientArgs();
    ASSERT_EQ(args.size(), 4u);
    ASSERT_EQ(args[0], "--key");
    ASSERT_EQ(args[2], "--server-key");
    auto keyed = [&](DisplayNodeRun& r) {
        r.keyFile = args[1];
        r.serverKeyFile = args[3];
    };
    auto left = std::make_unique<NodeThread>(master.endpoint(), "left", keyed);
    auto right = std::make_unique<NodeThread>(master.endpoint(), "right", keyed);
    ClientSettings keys;
    keys.keyFile = args[1];
    keys.serverKeyFile = args[3];
    clients.start(master.endpoint(), 2, 5000, keys);
    ASSERT_TRUE(master.waitForClients(2, 20000));
    ASSERT_TRUE(waitFor(*left, [&] { return !left->wall.empty(); }));
    ASSERT_TRUE(waitFor(*right, [&] { return !right->wall.empty(); }));

    const Scene reference(scene);
    const Image one = renderFrame(reference, Camera(scene.cameras.front(), 64, 48), scene.settings);
    auto presentsFrame = [&](const char* when) {
        FrameReport report;
        master.renderFrame(&report);
        for (NodeThread* node : {left.get(), right.get()}) {
            const uint64_t bit = node == left.get() ? 1 : 2;
            ASSERT_TRUE(waitFor(*node, [&] { return !node->shown.empty() && node->shown.back().frame == report.frame; }))
                << when << ": node " << bit;
            std::lock_guard lock(node->m);
            ASSERT_TRUE(node->shown.back().image.has_value()) << when << ": node " << bit;
            EXPECT_TRUE(sameOnNode(*node->shown.back().image, one, bit)) << when << ": node " << bit;
        }
    };
    presentsFrame("with keys");

    // The master vouches for each node's tile key: a keyed client of the master reads them.
    const KeyPair local = readKeyPair(args[1]);
    const std::string masterKey = readPublicKey(args[3]);
    zmq::context_t ctx{1};
    ListReader reader(ctx, master.endpoint(), &local, masterKey);
    Peers peers({&reader});
    ASSERT_TRUE(waitFor(reader, [&] { return !reader.lists.empty() && reader.lists.back().nodes.size() == 2; }));
    NodeList list;
    {
        std::lock_guard lock(reader.m);
        list = reader.lists.back();
    }
    EXPECT_EQ(list.nodes[0].serverKey.size(), 40u);
    EXPECT_EQ(list.nodes[1].serverKey.size(), 40u);
    EXPECT_NE(list.nodes[0].serverKey, list.nodes[1].serverKey);  // each node has its own pair
    EXPECT_NE(list.nodes[0].serverKey, local.publicKey);

    // A stranger with the node's server key but a key of its own: refused by the node's ZAP.
    const KeyPair strangerKeys = makeKeyPair();
    zmq::socket_t stranger(ctx, zmq::socket_type::dealer);
    stranger.set(zmq::sockopt::linger, 0);
    stranger.set(zmq::sockopt::curve_serverkey, list.nodes[0].serverKey);
    stranger.set(zmq::sockopt::curve_publickey, strangerKeys.publicKey);
    stranger.set(zmq::sockopt::curve_secretkey, strangerKeys.secretKey);
    ASSERT_EQ(zmq_socket_monitor(stranger.handle(), "inproc://stranger-monitor", ZMQ_EVENT_HANDSHAKE_FAILED_AUTH), 0);
    zmq::socket_t monitor(ctx, zmq::socket_type::pair);
    monitor.set(zmq::sockopt::linger, 0);
    monitor.connect("inproc://stranger-monitor");
    stranger.connect(list.nodes[0].endpoint);
    Header h;
    h.session = 1;
    const std::vector<uint8_t> forged = encodeMessage(h, TileResult{0, 0, TileCodec::Raw, 1, std::vector<uint8_t>(16 * 16 * 3, 255)});
    stranger.send(zmq::buffer(forged), zmq::send_flags::dontwait);
    monitor.set(zmq::sockopt::rcvtimeo, 10000);
    zmq::message_t event;
    ASSERT_TRUE(monitor.recv(event)) << "the stranger was not told it was refused";
    uint16_t id = 0;
    std::memcpy(&id, event.data(), 2);
    EXPECT_EQ(id, ZMQ_EVENT_HANDSHAKE_FAILED_AUTH);
    EXPECT_TRUE(eventually([&] { return left->counters->refusedClients.load() >= 1; })) << "the node did not count the refusal";
    EXPECT_EQ(right->counters->refusedClients.load(), 0u);
    presentsFrame("after the stranger");
    EXPECT_EQ(master.counters().refused, 0u);  // the master saw nothing of it
    peers.remove(&reader);
    right.reset();
    left.reset();
}

// A node without keys at a keyed master does not get in, and says why; so does one whose key
// the master does not know. Neither hangs: each gives up after its idle time.
TEST(DisplayNodes, NodesWithoutKeysOrWithUnknownKeysAreRefusedByAKeyedMaster) {
    const SceneDesc scene = smallScene();
    const auto dir = test::scratchDir();
    writeNewKeyPair(dir / "master");
    writeNewKeyPair(dir / "stranger");
    ClusterSettings cs = nodeSettings();
    cs.keyFile = dir / "master.key";
    cs.localClients = 2;
    Master master(scene, cs);
    NodeThread keyless(master.endpoint(), "left", [](DisplayNodeRun& r) { r.exitAfterIdleMs = 1500; });
    NodeThread unknown(master.endpoint(), "right", [&](DisplayNodeRun& r) {
        r.exitAfterIdleMs = 1500;
        r.keyFile = dir / "stranger.key";
        r.serverKeyFile = dir / "master.pub";
    });
    ASSERT_TRUE(eventually([&] { return keyless.finished.load() && unknown.finished.load(); }));
    EXPECT_EQ(keyless.status.load(), 1);
    EXPECT_EQ(unknown.status.load(), 1);
    EXPECT_GE(keyless.counters->failedHandshakes.load(), 1u);
    EXPECT_GE(unknown.counters->refusedHandshakes.load(), 1u);
    EXPECT_TRUE(keyless.wall.empty());
    EXPECT_TRUE(unknown.wall.empty());
    EXPECT_GE(master.refusedConnections(), 1u);
    EXPECT_GE(master.counters().failedHandshakes, 1u);
}

// A node that gets through a keyed master's CURVE (its key is allowed) but offers no tile key
// would take pixels in the clear: the master refuses it, saying why.
TEST(DisplayNodes, AKeyedMasterRefusesANodeWithoutATileKey) {
    const auto dir = test::scratchDir();
    writeNewKeyPair(dir / "master");
    ClusterSettings cs = nodeSettings();
    cs.keyFile = dir / "master.key";
    cs.localClients = 2;
    const SceneDesc scene = smallScene();
    Master master(scene, cs);
    const std::vector<std::string> args = master.localClientArgs();
    ASSERT_EQ(args.size(), 4u);
    const KeyPair local = readKeyPair(args[1]);
    zmq::context_t ctx{1};
    FakeNode node(ctx, master.endpoint(), "left", false, &local, readPublicKey(args[3]));  // its NodeHello has no key
    Peers peers({&node});
    ASSERT_TRUE(waitFor(node, [&] { return node.goodbye.has_value(); }));
    EXPECT_NE(node.goodbye->find("has no tile key"), std::string::npos) << *node.goodbye;
    EXPECT_FALSE(node.index.has_value());
    EXPECT_GE(master.counters().refused, 1u);
    peers.remove(&node);
}

TEST(DisplayNodes, AKeyWithoutTheMastersKeyIsAnInputError) {
    const auto dir = test::scratchDir();
    writeNewKeyPair(dir / "node");
    DisplayNodeRun r;
    r.connect = "tcp://127.0.0.1:9";
    r.name = "left";
    r.keyFile = dir / "node.key";
    try {
        runDisplayNode(r);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--key needs --server-key"), std::string::npos) << e.what();
    }
}

// Where the clients are told to send a node's tiles.
TEST(DisplayNodes, TheAdvertisedEndpointIsTheBoundOneOrTheGivenHost) {
    EXPECT_EQ(advertisedNodeEndpoint("tcp://127.0.0.1:5601", ""), "tcp://127.0.0.1:5601");
    EXPECT_EQ(advertisedNodeEndpoint("tcp://10.0.0.7:5601", ""), "tcp://10.0.0.7:5601");
    EXPECT_EQ(advertisedNodeEndpoint("tcp://0.0.0.0:5601", "wall-pc-2"), "tcp://wall-pc-2:5601");
    EXPECT_EQ(advertisedNodeEndpoint("tcp://0.0.0.0:5601", "10.1.2.3"), "tcp://10.1.2.3:5601");
    EXPECT_EQ(advertisedNodeEndpoint("tcp://[::]:5601", "[fd00::7]"), "tcp://[fd00::7]:5601");
    for (const char* wildcard : {"tcp://0.0.0.0:5601", "tcp://[::]:5601", "tcp://*:5601"}) {
        try {
            advertisedNodeEndpoint(wildcard, "");
            ADD_FAILURE() << wildcard << ": no error";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("--advertise"), std::string::npos) << e.what();
        }
    }
    for (const char* bad : {"wall pc", "host:1", "-x", "[fd00::7", "[zz::1]", "0.0.0.0", "a/b", "caf\xc3\xa9"})
        EXPECT_THROW(advertisedNodeEndpoint("tcp://0.0.0.0:5601", bad), InputError) << bad;
    EXPECT_THROW(advertisedNodeEndpoint("tcp://0.0.0.0:5601", std::string(241, 'a')), InputError);
    EXPECT_THROW(advertisedNodeEndpoint("ipc:///tmp/x", ""), InputError);
}

// A node advertising a host name for its (loopback) bind: the clients reach it there. (A wildcard
// bind is not used here: tests listen on loopback only.)
TEST(DisplayNodes, ANodeIsReachedAtItsAdvertisedHost) {
    SceneDesc scene = smallScene();
    NodeWall w(scene, nodeSettings());
    ASSERT_TRUE(w.ready());
    w.left.reset();
    w.left = std::make_unique<NodeThread>(w.master->endpoint(), "left", [](DisplayNodeRun& r) {
        r.bind = "tcp://127.0.0.1:0";
        r.advertise = "localhost";
    });
    ASSERT_TRUE(waitFor(*w.left, [&] { return !w.left->wall.empty(); }));
    FrameReport report;
    bool together = false;
    for (int i = 0; i < 10 && !together; ++i) {
        w.master->renderFrame(&report);
        const auto shown = w.shownOf(*w.left, report.frame);
        together = shown && shown->image && shown->leftOut.empty();
    }
    EXPECT_TRUE(together) << "the node advertised as localhost never presented a frame";
}

// A master written by hand for one node thread ("left"): a ROUTER on loopback that the node
// joins and that sends it messages of session `session`, one by one.
struct HandMaster {
    explicit HandMaster(uint64_t sessionId) : session(sessionId) {
        socket.set(zmq::sockopt::linger, 0);
        socket.bind("tcp://127.0.0.1:0");
        node = std::make_unique<NodeThread>(socket.get(zmq::sockopt::last_endpoint), "left");
        socket.set(zmq::sockopt::rcvtimeo, 5000);
    }
    // The node's NodeHello (5 s). Fatal failures: call it in ASSERT_NO_FATAL_FAILURE.
    void awaitHello() {
        zmq::message_t identity, msg;
        ASSERT_TRUE(socket.recv(identity));
        ASSERT_TRUE(socket.recv(msg));
        const auto* p = static_cast<const uint8_t*>(msg.data());
        ASSERT_EQ(decodeHeader(p, msg.size()).type, MsgType::NodeHello);
        hello = decodePayload<NodeHello>(p + kHeaderSize, msg.size() - kHeaderSize);
        peer = identity.to_string();
    }
    template <class Msg> void put(const Msg& msg, uint32_t frame = 0) {
        Header h;
        h.session = session;
        h.frame = frame;
        const std::vector<uint8_t> bytes = encodeMessage(h, msg);
        socket.send(zmq::buffer(peer), zmq::send_flags::sndmore);
        socket.send(zmq::buffer(bytes));
    }
    uint64_t session;
    zmq::context_t ctx{1};
    zmq::socket_t socket{ctx, zmq::socket_type::router};
    std::unique_ptr<NodeThread> node;  // destroyed (stopped and joined) before the socket
    std::string peer;
    NodeHello hello;
};

// A hostile master (a ROUTER of the test's) sends a display node NodeFrames and welcomes whose
// new fields (protocol 12) are out of range: the node drops and counts each, never crashes or
// hangs, and still assembles, accumulates and presents a good frame after them.
TEST(DisplayNodes, ANodeDropsMalformedViewsEyesAndKeysFromAHostileMaster) {
    HandMaster hand(77);
    ASSERT_NO_FATAL_FAILURE(hand.awaitHello());
    EXPECT_TRUE(hand.hello.publicKey.empty());  // no keys, no tile key
    // A welcome with a client key that is not Z85: dropped (the node stays out of the session).
    NodeWelcome badWelcome{0, 50, 5000, "[wall]\n", {std::string(40, '~')}};
    hand.put(badWelcome);
    ASSERT_TRUE(eventually([&] { return hand.node->counters->droppedMessages.load() >= 1; }));
    EXPECT_TRUE(hand.node->wall.empty());
    hand.put(NodeWelcome{0, 50, 5000, "[wall]\n", {}});
    ASSERT_TRUE(waitFor(*hand.node, [&] { return !hand.node->wall.empty(); }));

    SceneDesc scene = smallScene();
    scene.settings.gi = true;
    const std::vector<FrameView> views{{eyeCamera(scene, -0.2f), {}, 0, 0}, {eyeCamera(scene, 0.2f), {}, 0, 0}};
    const std::vector<uint64_t> masks = viewHalves(64, 48, 16, views);
    hand.put(TileRoutes{1, masks}, 1);
    const NodeFrame good{1, 64, 48, 16, TilePixels::Srgb8, views, {0, 1}, true, 5};
    std::vector<NodeFrame> bad;
    NodeFrame f = good;
    f.eyes = {0};  // an eye short
    bad.push_back(f);
    f = good;
    f.eyes = {0, 2};  // no such eye
    bad.push_back(f);
    f = good;
    f.pixels = TilePixels::LinearHalf;
    f.stochastic = false;  // linear tiles of a frame that does not accumulate
    bad.push_back(f);
    f = good;
    f.views = std::vector<FrameView>(kMaxViews + 1, views[0]);  // more views than a frame has
    f.eyes.clear();  // (the writer refuses more eyes than that; the reader stops at the views)
    bad.push_back(f);
    f = good;
    f.views[1].regions = {{60, 0, 10, 10}};  // a region outside its reference image
    f.views[1].refWidth = 64;
    f.views[1].refHeight = 48;
    bad.push_back(f);
    const uint64_t before = hand.node->counters->droppedMessages.load();
    for (const NodeFrame& b : bad) hand.put(b, 1);
    ASSERT_TRUE(eventually([&] { return hand.node->counters->droppedMessages.load() >= before + bad.size(); }));
    EXPECT_EQ(hand.node->counters->droppedMessages.load(), before + bad.size());
    // Views whose tiling does not match the masks: the frame is skipped, not assembled.
    f = good;
    f.views.push_back(views[0]);
    f.eyes.push_back(-1);
    hand.put(f, 1);
    hand.put(NodeSwap{1, {}}, 1);
    ASSERT_TRUE(waitFor(*hand.node, [&] { return !hand.node->shown.empty(); }));
    {
        std::lock_guard lock(hand.node->m);
        EXPECT_FALSE(hand.node->shown.back().image.has_value());  // it did not hold the frame
    }
    EXPECT_FALSE(hand.node->finished.load());

    // Then a good stereo frame: its tiles (from a test client on the node's tile socket) are
    // assembled into both eyes.
    hand.put(good, 1);
    zmq::socket_t client(hand.ctx, zmq::socket_type::dealer);
    client.set(zmq::sockopt::linger, 0);
    client.connect(hand.hello.endpoint);
    const std::vector<ViewTile> tiles = viewTiles(views, 64, 48, 16);
    for (uint32_t t = 0; t < tiles.size(); ++t) {
        if (!(masks[t] & 1)) continue;
        const std::vector<uint8_t> pixels(size_t(tiles[t].rect.width()) * tiles[t].rect.height() * 3, uint8_t(10 + tiles[t].view * 100));
        Header h;
        h.session = 77;
        h.frame = 1;
        client.send(zmq::buffer(encodeMessage(h, TileResult{1, t, TileCodec::Raw, 1, pixels})), zmq::send_flags::dontwait);
    }
    hand.socket.set(zmq::sockopt::rcvtimeo, 100);
    bool have = false;
    for (int i = 0; i < 100 && !have; ++i) {
        zmq::message_t from, msg;
        if (!hand.socket.recv(from) || !hand.socket.recv(msg)) continue;
        const Header h = decodeHeader(static_cast<const uint8_t*>(msg.data()), msg.size());
        have = h.type == MsgType::NodeHave;
    }
    ASSERT_TRUE(have) << "the node never held the good frame";
    hand.put(NodeSwap{1, {}}, 1);
    ASSERT_TRUE(waitFor(*hand.node, [&] { return hand.node->shown.size() >= 2; }));
    std::lock_guard lock(hand.node->m);
    const NodeThread::Shown& shown = hand.node->shown.back();
    ASSERT_TRUE(shown.image && shown.right);
    EXPECT_EQ(shown.image->pixel(0, 0)[0], 10);
    EXPECT_EQ(shown.right->pixel(0, 0)[0], 110);
}

TEST(DisplayNodes, ANodeTheWallDoesNotNameIsRefused) {
    Wall w;
    FakeNode stranger(w.ctx, w.master.endpoint(), "attic");
    w.peers.add(&stranger);
    ASSERT_TRUE(waitFor(stranger, [&] { return stranger.goodbye.has_value(); }));
    EXPECT_NE(stranger.goodbye->find("no display node 'attic'"), std::string::npos) << *stranger.goodbye;
    EXPECT_FALSE(stranger.index.has_value());
    EXPECT_GE(w.master.counters().refused, 1u);
    w.peers.remove(&stranger);
}

TEST(DisplayNodes, AWallWithoutNodesRefusesANode) {
    SceneDesc scene = smallScene();
    Master master(scene, test::inStep());
    zmq::context_t ctx{1};
    FakeNode node(ctx, master.endpoint(), "left");
    Peers peers({&node});
    ASSERT_TRUE(waitFor(node, [&] { return node.goodbye.has_value(); }));
    EXPECT_NE(node.goodbye->find("has no display nodes"), std::string::npos) << *node.goodbye;
    peers.remove(&node);
}

// With async frames the master begins frame N+1 on N's last ack, so N+1's NodeFrame can reach a
// node before N's last tile, and N's swap always comes after N+1 began. A scripted master: the
// node keeps both frames, reports and presents them in order (N+1 only once N is swapped), and a
// frame it was left out of (released before it held it) lets the next one through.
TEST(DisplayNodes, FramesThatOverlapArePresentedInOrderAndALeftOutFrameLetsTheNextThrough) {
    HandMaster hand(31);
    ASSERT_NO_FATAL_FAILURE(hand.awaitHello());
    hand.put(NodeWelcome{0, 50, 5000, "[wall]\n", {}});
    ASSERT_TRUE(waitFor(*hand.node, [&] { return !hand.node->wall.empty(); }));
    const int w = 32, hgt = 32, ts = 16;
    const std::vector<TileRect> rects = makeTiles(w, hgt, ts);
    hand.put(TileRoutes{1, std::vector<uint64_t>(rects.size(), 1)}, 1);
    zmq::socket_t client(hand.ctx, zmq::socket_type::dealer);
    client.set(zmq::sockopt::linger, 0);
    client.connect(hand.hello.endpoint);
    auto tile = [&](uint32_t frame, uint32_t t) {
        const std::vector<uint8_t> pixels(size_t(rects[t].width()) * rects[t].height() * 3, uint8_t(10 * frame));
        Header h;
        h.session = 31;
        h.frame = frame;
        client.send(zmq::buffer(encodeMessage(h, TileResult{frame, t, TileCodec::Raw, 1, pixels})), zmq::send_flags::dontwait);
    };
    // The NodeHave frames the node sends within `ms`.
    auto haves = [&](int ms) {
        std::vector<uint32_t> out;
        hand.socket.set(zmq::sockopt::rcvtimeo, 20);
        const auto end = Clock::now() + std::chrono::milliseconds(ms);
        while (Clock::now() < end) {
            zmq::message_t from, msg;
            if (!hand.socket.recv(from)) continue;
            if (!hand.socket.recv(msg)) continue;
            const auto* b = static_cast<const uint8_t*>(msg.data());
            if (decodeHeader(b, msg.size()).type == MsgType::NodeHave)
                out.push_back(decodePayload<NodeHave>(b + kHeaderSize, msg.size() - kHeaderSize).frame);
        }
        return out;
    };
    auto frameMsg = [&](uint32_t n) { return NodeFrame{n, w, hgt, ts, TilePixels::Srgb8, {}, {}, false, 1}; };

    // Frame 1 lacks its last tile when frame 2 begins; frame 2 comes whole.
    hand.put(frameMsg(1), 1);
    for (uint32_t t = 0; t + 1 < rects.size(); ++t) tile(1, t);
    hand.put(frameMsg(2), 2);
    for (uint32_t t = 0; t < rects.size(); ++t) tile(2, t);
    EXPECT_TRUE(haves(300).empty()) << "frame 2 is not reported before frame 1";
    tile(1, uint32_t(rects.size() - 1));
    EXPECT_EQ(haves(300), std::vector<uint32_t>{1}) << "frame 1 held; frame 2 waits for its swap";
    hand.put(NodeSwap{1, {}}, 1);
    EXPECT_EQ(haves(300), std::vector<uint32_t>{2}) << "frame 2 reported once frame 1 swapped";
    hand.put(NodeSwap{2, {}}, 2);
    ASSERT_TRUE(waitFor(*hand.node, [&] { return hand.node->shown.size() >= 2; }));
    {
        std::lock_guard lock(hand.node->m);
        ASSERT_EQ(hand.node->shown.size(), 2u);
        EXPECT_EQ(hand.node->shown[0].frame, 1u);
        ASSERT_TRUE(hand.node->shown[0].image);
        EXPECT_EQ(hand.node->shown[0].image->pixel(0, 0)[0], 10);
        EXPECT_EQ(hand.node->shown[1].frame, 2u);
        ASSERT_TRUE(hand.node->shown[1].image);
        EXPECT_EQ(hand.node->shown[1].image->pixel(0, 0)[0], 20);
    }

    // Frame 3 never completes here; frame 4 does, and waits behind it until the master releases
    // frame 3 without this hand.node->
    hand.put(frameMsg(3), 3);
    tile(3, 0);
    hand.put(frameMsg(4), 4);
    for (uint32_t t = 0; t < rects.size(); ++t) tile(4, t);
    EXPECT_TRUE(haves(300).empty());
    hand.put(NodeSwap{3, {"left"}}, 3);
    EXPECT_EQ(haves(300), std::vector<uint32_t>{4}) << "frame 3 let go at its swap";
    hand.put(NodeSwap{4, {}}, 4);
    ASSERT_TRUE(waitFor(*hand.node, [&] { return hand.node->shown.size() >= 4; }));
    std::lock_guard lock(hand.node->m);
    EXPECT_FALSE(hand.node->shown[2].image) << "frame 3 was not held";
    ASSERT_TRUE(hand.node->shown[3].image);
    EXPECT_EQ(hand.node->shown[3].frame, 4u);
    EXPECT_EQ(hand.node->shown[3].image->pixel(0, 0)[0], 40);
}

}  // namespace
}  // namespace rtwall
