// The operator console's picture of a wall on display nodes, the master's side (issue 31,
// Master::nodePicture): honest nodes (runDisplayNode threads) answer with the pixels they own
// and the picture is the one-PC frame byte for byte; a node that leaves is named missing; a
// hostile node (a scripted DEALER) that is silent, sends cells outside the picture, more than a
// cell's pixels, another frame size, a broken stream or an undecodable part is dropped and named
// missing, the honest node's pixels stay exact, and the master keeps rendering.
#include "codec.h"
#include "protocol.h"
#include "test_util.h"

#include <rtwall/cluster.h>
#include <rtwall/image_box.h>

#include <gtest/gtest.h>
#include <zmq.hpp>

#include <atomic>
#include <thread>

namespace rtwall {
namespace {

using namespace cluster;

constexpr int kW = 160, kH = 120;

// Render clients on threads, joined at the end (the master's goodbye ends each).
struct ClientThreads {
    std::vector<std::thread> threads;
    ~ClientThreads() {
        for (std::thread& t : threads) t.join();
    }
    void start(const std::string& endpoint) {
        ClientSettings c;
        c.connect = endpoint;
        c.threads = 1;
        c.exitAfterIdleMs = 5000;
        threads.emplace_back([c] { runClient(c); });
    }
};

// Left of the middle: node 0's where it is asked; right: node 1's, else node 0's.
std::vector<uint8_t> halves(int w, int h, int, uint64_t nodes) {
    std::vector<uint8_t> o(size_t(w) * h, 0xFF);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const bool right = x >= w / 2;
            if (right && (nodes & 2)) o[size_t(y) * w + x] = 1;
            else if (nodes & 1) o[size_t(y) * w + x] = 0;
        }
    return o;
}

class NodeThread {
public:
    NodeThread(const std::string& endpoint, const std::string& name) {
        run_.connect = endpoint;
        run_.name = name;
        run_.exitAfterIdleMs = 5000;
        run_.stop = &stop_;
        run_.onWall = [](const std::string&) {};
        run_.present = [](uint32_t, const Image*, const Image*, const std::vector<std::string>&) {};
        run_.previewOwners = halves;
        thread_ = std::thread([this] { runDisplayNode(run_); });
    }
    ~NodeThread() { stop(); }
    void stop() {
        stop_ = true;
        if (thread_.joinable()) thread_.join();
    }

private:
    DisplayNodeRun run_;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

// Node "right" written by hand: it joins, beats, never holds a frame (the barrier leaves it
// out), and answers each picture ask as `mode` says.
class HostileNode {
public:
    enum Mode { Silent, OutsideThePicture, MoreThanACell, OtherFrameSize, BrokenStream, Undecodable };
    std::atomic<int> mode{Silent};

    explicit HostileNode(const std::string& endpoint) : socket_(ctx_, zmq::socket_type::dealer) {
        socket_.set(zmq::sockopt::linger, 0);
        socket_.connect(endpoint);
        put(Header{}, NodeHello{kProtocolVersion, "right", "tcp://127.0.0.1:9", ""});
        thread_ = std::thread([this] { loop(); });
    }
    ~HostileNode() {
        stop_ = true;
        thread_.join();
    }

private:
    template <class Msg> void put(Header h, const Msg& m) {
        const std::vector<uint8_t> bytes = encodeMessage(h, m);
        socket_.send(zmq::buffer(bytes), zmq::send_flags::dontwait);
    }
    template <class Msg> void answer(const Msg& m) {
        Header h;
        h.session = session_;
        put(h, m);
    }
    void loop() {
        auto beat = std::chrono::steady_clock::now();
        while (!stop_) {
            zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
            zmq::poll(&item, 1, std::chrono::milliseconds(10));
            zmq::message_t msg;
            while (socket_.recv(msg, zmq::recv_flags::dontwait)) {
                const auto* p = static_cast<const uint8_t*>(msg.data());
                const Header h = decodeHeader(p, msg.size());
                if (h.type == MsgType::NodeWelcome) {
                    session_ = h.session;
                    answer(Heartbeat{});
                } else if (h.type == MsgType::NodePreviewAsk) {
                    onAsk(decodePayload<NodePreviewAsk>(p + kHeaderSize, msg.size() - kHeaderSize));
                }
            }
            if (session_ && std::chrono::steady_clock::now() - beat > std::chrono::milliseconds(50)) {
                beat = std::chrono::steady_clock::now();
                answer(Heartbeat{});
            }
        }
    }
    void onAsk(const NodePreviewAsk& ask) {
        std::vector<uint32_t> cell = {255, 255, 255, 1};
        std::vector<uint8_t> z, scratch;
        NodePreview part{ask.id, 1, 0, kW, kH, 0, 0, 1, 1, 1, true, {}};
        switch (Mode(mode.load())) {
        case Silent: return;
        case OutsideThePicture: part.x0 = kW, part.x1 = kW + 1; break;
        case MoreThanACell: cell[3] = 2, cell[0] = 300, part.valueBytes = 2; break;
        case OtherFrameSize: part.srcWidth = kW + 2; break;
        case BrokenStream: part.cells = {0x28, 0xB5, 0x2F, 0xFD, 1, 2, 3}; break;
        case Undecodable: {
            part.valueBytes = 2;
            encodePreviewCells(cell.data(), 1, 2, part.cells, scratch);
            Header h;
            h.session = session_;
            std::vector<uint8_t> bytes = encodeMessage(h, part);
            bytes[kHeaderSize + 4 + 4 + 1 + 6 * 4] = 3;  // valueBytes 3
            socket_.send(zmq::buffer(bytes), zmq::send_flags::dontwait);
            return;
        }
        }
        if (part.cells.empty()) encodePreviewCells(cell.data(), 1, part.valueBytes, part.cells, scratch);
        answer(part);
    }

    zmq::context_t ctx_{1};
    zmq::socket_t socket_;
    std::atomic<bool> stop_{false};
    uint64_t session_ = 0;
    std::thread thread_;
};

ClusterSettings nodesSettings() {
    ClusterSettings cs;
    cs.async = false;
    cs.displayNodes.names = {"left", "right"};
    cs.displayNodes.wallText = "[wall]\n";
    cs.displayNodes.stallSeconds = 0.3;  // the hostile node never holds a frame: released without it
    return cs;
}

// The one-PC frame of `view`.
Image onePcFrame(const SceneDesc& scene, const FrameView& view) {
    ClientThreads clients;
    ClusterSettings cs;
    cs.async = false;
    Master m(scene, cs);
    clients.start(m.endpoint());
    EXPECT_TRUE(m.waitForClients(1, 20000));
    m.setViews({view});
    FrameReport r;
    std::vector<Image> images = m.renderViews(&r);
    Compositor c;
    ComposeFrame f;
    f.views = {view};
    f.eyes = {-1};
    return c.compose(f, images).left;
}

// The scene, its one view, and that view's one-PC frame.
struct OnePc {
    SceneDesc scene = test::demoScene(kW, kH);
    FrameView view;
    Image frame;
    OnePc() {
        view.camera = scene.cameras.front();
        frame = onePcFrame(scene, view);
    }
};

// The pixels of `im` where `keep(x)`, the others black.
Image only(const Image& im, bool (*keep)(int x)) {
    Image out = im;
    for (int y = 0; y < im.height; ++y)
        for (int x = 0; x < im.width; ++x)
            if (!keep(x)) std::fill_n(out.pixel(x, y), 3, uint8_t(0));
    return out;
}

// Renders one frame and waits (bounded) until the barrier released it to the nodes there.
void renderAndSwap(Master& m) {
    FrameReport r;
    m.renderViews(&r);
    ASSERT_TRUE(m.waitForSwap(r.frame, 10000));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the nodes read their swap
}

TEST(NodePicture, TwoHonestNodesGiveTheOnePcFrameAndALeavingOneIsNamed) {
    const OnePc ref;
    ClientThreads clients;
    Master m(ref.scene, nodesSettings());
    auto left = std::make_unique<NodeThread>(m.endpoint(), "left");
    auto right = std::make_unique<NodeThread>(m.endpoint(), "right");
    ASSERT_TRUE(m.waitForDisplayNodes(20000));
    // Before any frame: the nodes answer that they presented none, and are not in the picture.
    std::optional<NodePicture> pic = m.nodePicture(kW, 10000);
    ASSERT_TRUE(pic);
    EXPECT_EQ(pic->frame, 0u);
    EXPECT_TRUE(pic->left.rgb.empty());
    EXPECT_EQ(pic->missing, (std::vector<std::string>{"left", "right"}));

    clients.start(m.endpoint());
    ASSERT_TRUE(m.waitForClients(1, 20000));
    m.setViews({ref.view});
    ASSERT_NO_FATAL_FAILURE(renderAndSwap(m));
    pic = m.nodePicture(kW, 10000);
    ASSERT_TRUE(pic);
    EXPECT_TRUE(pic->missing.empty());
    EXPECT_TRUE(pic->oneFrame);
    EXPECT_GT(pic->frame, 0u);
    EXPECT_EQ(pic->left.rgb, ref.frame.rgb) << "every pixel, each from its one node";
    EXPECT_TRUE(pic->right.rgb.empty());
    pic = m.nodePicture(37, 10000);
    ASSERT_TRUE(pic);
    EXPECT_EQ(pic->left.rgb, boxPicture(ref.frame, 37).rgb) << "the sums of both nodes' cells make the whole's picture";
    EXPECT_THROW(m.nodePicture(0, 100), std::invalid_argument);

    // The right node leaves: the left one, the only one asked, owns every pixel (it holds every
    // tile here); the right one is named all the same.
    right->stop();
    for (int i = 0; i < 400 && m.displayNodesPresent().size() != 1; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    ASSERT_EQ(m.displayNodesPresent(), std::vector<std::string>{"left"});
    pic = m.nodePicture(kW, 10000);
    ASSERT_TRUE(pic);
    EXPECT_EQ(pic->missing, std::vector<std::string>{"right"});
    EXPECT_EQ(pic->left.rgb, ref.frame.rgb);
    left->stop();
    for (int i = 0; i < 400 && !m.displayNodesPresent().empty(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_FALSE(m.nodePicture(kW, 1000)) << "no node there: no picture";
}

class NodePictureAttack : public ::testing::TestWithParam<int> {};

TEST_P(NodePictureAttack, AHostileNodeIsNamedMissingAndTheHonestPixelsStayExact) {
    const OnePc ref;
    ClientThreads clients;
    Master m(ref.scene, nodesSettings());
    NodeThread left(m.endpoint(), "left");
    HostileNode right(m.endpoint());
    right.mode = GetParam();
    ASSERT_TRUE(m.waitForDisplayNodes(20000));
    clients.start(m.endpoint());
    ASSERT_TRUE(m.waitForClients(1, 20000));
    m.setViews({ref.view});
    ASSERT_NO_FATAL_FAILURE(renderAndSwap(m));
    const uint64_t droppedBefore = m.droppedMessages();
    const auto start = std::chrono::steady_clock::now();
    const std::optional<NodePicture> pic = m.nodePicture(kW, 1500);
    ASSERT_TRUE(pic);
    EXPECT_EQ(pic->missing, std::vector<std::string>{"right"});
    // The left half is the left node's, exactly; the right half black but for what a dropped
    // part may have put there (nothing: every part here is refused whole).
    EXPECT_EQ(pic->left.rgb, only(ref.frame, [](int x) { return x < kW / 2; }).rgb);
    if (GetParam() == HostileNode::Silent) {
        EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(1400)) << "it waited for the silent node";
    } else {
        EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(1400)) << "a wrong answer ends the wait";
        // Counted by the network thread as it drops the part (an undecodable one just after
        // the picture stopped waiting for its node).
        for (int i = 0; i < 200 && m.droppedMessages() == droppedBefore; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
        EXPECT_GT(m.droppedMessages(), droppedBefore);
    }
    // The wall goes on.
    ASSERT_NO_FATAL_FAILURE(renderAndSwap(m));
}

INSTANTIATE_TEST_SUITE_P(Modes, NodePictureAttack,
                         ::testing::Values(int(HostileNode::Silent), int(HostileNode::OutsideThePicture),
                                           int(HostileNode::MoreThanACell), int(HostileNode::OtherFrameSize),
                                           int(HostileNode::BrokenStream), int(HostileNode::Undecodable)));

}  // namespace
}  // namespace rtwall
