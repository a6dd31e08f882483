// A display node's network side (issue 19): a DEALER to the master for control (NodeHello,
// NodeFrame, NodeHave, NodeSwap, NodeSwapped) and a ROUTER on which the render clients deliver
// the tiles its screens show. Tiles are decoded on this thread straight into a FrameAssembler
// that holds only the tiles routed to this node (one image per view); a tile that comes before
// its frame's NodeFrame (it travels on another connection) waits in a bounded queue. A frame it
// holds becomes what it shows (the Compositor: accumulated and composed into the eyes as on the
// single-PC wall) before it says so; the swap presents that. What is presented, and how, is the caller's callback.
// A re-projecting wall (issue 27) makes each released frame the warp's source at its swap and
// presents at every pose the master sends (NodePose, once per refresh), warped to that pose.
// The frame it presented last stays until the next swap, for the operator console's picture
// (NodePreviewAsk, issue 31): the node answers with the cells of the pixels it owns.
#include "codec.h"
#include "link_socket.h"
#include "net.h"
#include "protocol.h"
#include "security.h"

#include <rtwall/cluster.h>
#include <rtwall/image_box.h>

#include <zmq.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <optional>
#include <thread>
#include <vector>

namespace rtwall {

using namespace cluster;

namespace {

// Tiles of frames this node has not begun yet: more are dropped (and the frame is then missed).
constexpr size_t kMaxEarlyTiles = 4096;

class DisplayNode {
public:
    explicit DisplayNode(const DisplayNodeRun& run) : run_(run) {
        if (!run.keyFile.empty()) {
            // As `rtwall client`: the same options, the same checks.
            if (run.serverKeyFile.empty()) throw InputError("--key needs --server-key (the master's public key)");
            checkZmqVersion();
            keys_ = readKeyPair(run.keyFile);
            serverKey_ = readPublicKey(run.serverKeyFile);
            tileKeys_ = makeKeyPair();
        }
    }

    int operator()() {
        tiles_.set(zmq::sockopt::linger, 0);
        tiles_.set(zmq::sockopt::maxmsgsize, int64_t(maxTileResultBytes()));
        tiles_.set(zmq::sockopt::rcvhwm, 100000);
        if (keyed()) {
            // A CURVE server for the clients' tiles, with a key pair of this run (the clients
            // learn its public key from the master); until the master's welcome names the client
            // keys, nobody gets in.
            zap_ = std::make_unique<ZapHandler>(ctx_, std::vector<std::string>{}, "rtwall display",
                                                "the client keys the master gave this node");
            tiles_.set(zmq::sockopt::zap_domain, "rtwall-node");
            setCurveServer(tiles_, tileKeys_.secretKey);
        }
        advertisedNodeEndpoint(run_.bind, run_.advertise);  // a wildcard without --advertise stops before listening
        tiles_.bind(run_.bind);
        endpoint_ = advertisedNodeEndpoint(tiles_.get(zmq::sockopt::last_endpoint), run_.advertise);
        connect();
        double idleSince = nowSeconds();
        for (;;) {
            zmq::pollitem_t items[] = {{master_.handle(), 0, ZMQ_POLLIN, 0}, {tiles_.handle(), 0, ZMQ_POLLIN, 0},
                                       {monitor_.handle(), 0, ZMQ_POLLIN, 0}};
            try {
                zmq::poll(items, monitor_ ? 3 : 2, std::chrono::milliseconds(10));
            } catch (const zmq::error_t& e) {
                // A signal (SIGTERM from `rtwall display`'s handler) interrupted the wait: the
                // stop flag is looked at below, as after any wait.
                if (e.num() != EINTR) throw;
                items[0].revents = items[1].revents = items[2].revents = 0;
            }
            if (monitor_ && (items[2].revents & ZMQ_POLLIN)) readMonitor();
            if (zap_ && run_.counters) run_.counters->refusedClients = zap_->denied();
            if (items[0].revents & ZMQ_POLLIN) {
                // Poses queued behind each other (a warp that took longer than a refresh): only
                // the newest is shown, after everything else that came (a swap before it too).
                zmq::message_t pose;
                for (int i = 0; i < 256; ++i) {
                    zmq::message_t msg;
                    if (!master_.recv(msg, zmq::recv_flags::dontwait)) break;
                    if (discardRestOf(master_, msg) > 0) continue;
                    if (isPose(msg)) {
                        if (pose.size() > 0 && run_.counters) ++run_.counters->supersededPoses;
                        pose = std::move(msg);
                        lastHeard_ = idleSince = nowSeconds();
                        continue;
                    }
                    const std::optional<int> status = fromMaster(msg);
                    if (status) return *status;
                    lastHeard_ = idleSince = nowSeconds();
                }
                if (pose.size() > 0)
                    if (const std::optional<int> status = fromMaster(pose)) return *status;
            }
            if (items[1].revents & ZMQ_POLLIN) {
                for (int i = 0; i < 1024; ++i) {
                    zmq::message_t identity, msg;
                    if (!tiles_.recv(identity, zmq::recv_flags::dontwait)) break;
                    if (!identity.more() || !tiles_.recv(msg, zmq::recv_flags::dontwait)) continue;
                    if (discardRestOf(tiles_, msg) > 0) continue;
                    onTile(std::move(msg));
                }
            }
            if (run_.stop && run_.stop->load()) {
                if (session_) send(Goodbye{"display node '" + run_.name + "' stops"});
                return 0;
            }
            const double now = nowSeconds();
            if (session_ && now - lastSent_ > heartbeatMs_ * 1e-3) send(Heartbeat{});
            if (now - lastHeard_ > timeoutMs_ * 1e-3) {
                if (run_.exitAfterIdleMs > 0 && now - idleSince > run_.exitAfterIdleMs * 1e-3) {
                    std::fprintf(stderr, "rtwall display: no master at %s for %d ms, giving up%s\n", run_.connect.c_str(),
                                 run_.exitAfterIdleMs,
                                 handshakes_.trouble().empty() ? "" : (" (" + handshakes_.trouble() + ")").c_str());
                    return 1;
                }
                // The master went silent: join again (a restarted master, or one that dropped us).
                connect();
            }
        }
    }

private:
    static double nowSeconds() {
        return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    }

    bool keyed() const { return !run_.keyFile.empty(); }

    // A NodePose of this session (the rest is looked at by fromMaster, which drops what is wrong).
    bool isPose(const zmq::message_t& msg) const {
        try {
            const Header h = decodeHeader(static_cast<const uint8_t*>(msg.data()), msg.size());
            return h.type == MsgType::NodePose && session_ != 0 && h.session == session_;
        } catch (const DecodeError&) {
            return false;
        }
    }

    void connect() {
        master_ = zmq::socket_t(ctx_, zmq::socket_type::dealer);
        // A welcome holds the wall config and the client keys.
        configureSocket(master_, int64_t(kHeaderSize + 64 + kMaxWallConfigBytes + kMaxClientKeys * 48 + (1 << 26)), 250, 3000);
        master_.set(zmq::sockopt::linger, 0);
        if (keyed()) setCurveClient(master_, serverKey_, keys_);
        // The handshake's outcome (a refused key, no CURVE on one side) is said in one line.
        monitor_.reset();
        monitor_.start(ctx_, master_, "inproc://rtwall-node-monitor-" + std::to_string(++monitorSeq_), kMasterLinkEvents);
        master_.connect(run_.connect);
        session_ = 0;
        shown_ = onScreen_ = {};
        onScreenFrame_ = 0;
        compositor_ = Compositor{};  // another session's frames: no running mean goes on across a rejoin
        reproject_ = false;          // until the welcome says
        sourceFrame_ = lastCounted_ = 0;
        leftOut_.clear();
        saidMismatch_ = false;
        routes_.clear();
        early_.clear();
        for (Slot& slot : store_) slot.begun = false;
        pendingSwap_.reset();
        sendNow(master_, encodeMessage(Header{}, NodeHello{kProtocolVersion, run_.name, endpoint_, tileKeys_.publicKey}));
        lastHeard_ = lastSent_ = nowSeconds();
    }

    template <class Msg> void send(const Msg& msg, uint32_t frame = 0) {
        Header h;
        h.session = session_;
        h.frame = frame;
        sendNow(master_, encodeMessage(h, msg));
        lastSent_ = nowSeconds();
    }

    std::optional<int> fromMaster(const zmq::message_t& msg) {
        const auto* bytes = static_cast<const uint8_t*>(msg.data());
        try {
            const Header h = decodeHeader(bytes, msg.size());
            const uint8_t* p = bytes + kHeaderSize;
            const size_t n = msg.size() - kHeaderSize;
            if (refuseOtherVersion(h, "rtwall display", "node")) return 1;
            if (h.type == MsgType::Goodbye) {
                std::fprintf(stderr, "rtwall display: the master says goodbye: %s\n", decodePayload<Goodbye>(p, n).reason.c_str());
                return 0;
            }
            if (h.type == MsgType::NodeWelcome) {
                const NodeWelcome w = decodePayload<NodeWelcome>(p, n);
                session_ = h.session;
                index_ = w.node;
                heartbeatMs_ = int(std::max(10u, w.heartbeatMs));
                timeoutMs_ = int(std::max(w.timeoutMs, 2 * w.heartbeatMs));
                reproject_ = w.reproject;
                if (zap_) zap_->setAllowed(w.clientKeys);
                // At once: the master tells the clients where this node is only once it answered
                // (its tile socket now lets their keys in).
                send(Heartbeat{});
                if (run_.onWall) run_.onWall(w.wall);
                std::fprintf(stderr, "rtwall display: node '%s' (%u) joined %s, tiles to %s\n", run_.name.c_str(), index_,
                             run_.connect.c_str(), endpoint_.c_str());
                return std::nullopt;
            }
            if (session_ == 0 || h.session != session_) return std::nullopt;  // another session, or before the welcome
            switch (h.type) {
            case MsgType::TileRoutes: {
                TileRoutes r = decodePayload<TileRoutes>(p, n);
                routes_[r.frame] = std::move(r.masks);
                while (routes_.size() > 2) routes_.erase(routes_.begin());
                break;
            }
            case MsgType::NodeFrame: onFrame(decodePayload<NodeFrame>(p, n)); break;
            case MsgType::NodePose: return onPose(decodePayload<NodePose>(p, n));
            case MsgType::NodePreviewAsk: onPreviewAsk(decodePayload<NodePreviewAsk>(p, n)); break;
            case MsgType::NodeSwap: {
                const NodeSwap s = decodePayload<NodeSwap>(p, n);
                // Frames before this one were released without this node (it was late): let them
                // go, shown or not, so that this one can be shown if it is held.
                if (pendingSwap_ && *pendingSwap_ < s.frame) pendingSwap_.reset();
                for (Slot& slot : store_)
                    if (slot.begun && slot.frame.frame < s.frame) slot.begun = false;
                reportIfComplete();  // the released frame, if it was held back behind the one before
                const bool held = pendingSwap_ == s.frame;
                if (reproject_) {
                    // The frame becomes the warp's newest source; the poses show it.
                    if (const Slot* slot = held ? slotOf(s.frame) : nullptr) keepSource(*slot, s.leftOut);
                } else {
                    if (held) {
                        // What it shows now stays until the next swap; the next frame is composed
                        // into the other buffers.
                        std::swap(onScreen_, shown_);
                        onScreenFrame_ = s.frame;
                    }
                    if (held && run_.roomEyes)
                        if (const Slot* slot = slotOf(s.frame); slot && slot->frame.roomEyes) run_.roomEyes(*slot->frame.roomEyes);
                    if (run_.present) {
                        if (held) run_.present(s.frame, &onScreen_.left, onScreen_.right.rgb.empty() ? nullptr : &onScreen_.right, s.leftOut);
                        else run_.present(s.frame, nullptr, nullptr, s.leftOut);
                    }
                }
                send(NodeSwapped{s.frame}, s.frame);
                // Frames up to this one are done with: shown, or released without this node.
                if (held) pendingSwap_.reset();
                for (Slot& slot : store_)
                    if (slot.begun && slot.frame.frame <= s.frame) slot.begun = false;
                reportIfComplete();
                if (held && !reproject_ && run_.frames > 0 && ++presented_ >= run_.frames) {
                    send(Goodbye{"display node '" + run_.name + "' presented its frames"});
                    return 0;
                }
                break;
            }
            default: break;  // heartbeats, and types a node never gets
            }
        } catch (const DecodeError& e) {
            if (run_.counters) ++run_.counters->droppedMessages;
            std::fprintf(stderr, "rtwall display: dropped a malformed message from the master: %s\n", e.what());
        }
        return std::nullopt;
    }

    void onFrame(const NodeFrame& f) {
        auto r = routes_.upper_bound(f.frame);
        if (r == routes_.begin()) {
            std::fprintf(stderr, "rtwall display: frame %u came without its tile masks; it is skipped\n", f.frame);
            return;
        }
        // The newest frame goes into the older slot: the frame before may still be waiting for
        // its last tiles or its swap (the master begins frame N+1 on N's last ack, which can
        // overtake N's last tile on its way here, and N's NodeSwap comes after N+1 began).
        // Re-projecting, a frame reported and not yet swapped is composed only at its swap: a
        // frame that came in the meantime must not overwrite it. It is parked (its buffers
        // trade places with the parked slot's, nothing is copied).
        if (reproject_ && slots_[current_ ^ 1]->begun && pendingSwap_ == slots_[current_ ^ 1]->frame.frame)
            std::swap(slots_[current_ ^ 1], parked_);
        Slot& slot = *slots_[current_ ^ 1];
        try {
            // The clients' tiling of the frame (viewTiles), which the masks index.
            std::vector<ViewTile> tiles;
            if (f.views.empty())
                for (const TileRect& t : makeTiles(f.width, f.height, f.tileSize)) tiles.push_back({0, t});
            else
                tiles = viewTiles(f.views, f.width, f.height, f.tileSize);
            FrameHolding held;
            held.linear = f.pixels == TilePixels::LinearHalf;
            held.depth = f.depth;
            held.features = f.denoise ? f.denoise->features : 0;
            held.routes = &std::prev(r)->second;
            held.node = index_;
            slot.assembly.beginFrame(f.frame, f.width, f.height, tiles, uint32_t(f.views.size()), held);
            // What this node holds of each view: the bounding box of its routed tiles (its
            // screens and the ring around them). Re-projecting warps only that.
            slot.held.assign(std::max<size_t>(1, f.views.size()), TileRect{});
            for (size_t t = 0; t < tiles.size(); ++t) {
                if (!(((*held.routes)[t] >> index_) & 1) || tiles[t].view >= slot.held.size()) continue;
                TileRect& box = slot.held[tiles[t].view];
                const TileRect& rect = tiles[t].rect;
                box = box.width() <= 0 || box.height() <= 0 ? rect : TileRect{std::min(box.x0, rect.x0), std::min(box.y0, rect.y0), std::max(box.x1, rect.x1), std::max(box.y1, rect.y1)};
            }
        } catch (const std::invalid_argument& e) {
            std::fprintf(stderr, "rtwall display: frame %u is skipped: %s\n", f.frame, e.what());
            return;
        }
        // The windows a denoised frame is filtered in: this node's screens' (the wall's).
       
        if (f.denoise && run_.denoiseWindows) {
            try {
                const std::vector<int> eyes(f.eyes.begin(), f.eyes.end());
                slot.windows = run_.denoiseWindows(f.width, f.height, f.views, eyes, index_);
            } catch (const std::exception& e) {
               
                if (!saidWindows_)
                    std::fprintf(stderr, "rtwall display: frame %u is denoised whole, not by screens: %s\n", f.frame, e.what());
                saidWindows_ = true;
            }
        }
        current_ ^= 1;
        slot.begun = true;
        slot.frame = f;
        slot.haveSent = false;
        // The tiles that came first.
        std::vector<zmq::message_t> early;
        early.swap(early_);
        for (zmq::message_t& m : early) onTile(std::move(m));
        reportIfComplete();
    }

    void onTile(zmq::message_t msg) {
        const auto* bytes = static_cast<const uint8_t*>(msg.data());
        TileResult r;
        try {
            const Header h = decodeHeader(bytes, msg.size());
            if (h.type != MsgType::TileResult || h.version != kProtocolVersion || session_ == 0 || h.session != session_) return;
            r = decodeMessage<TileResult>(bytes, msg.size());
        } catch (const DecodeError&) {
            if (run_.counters) ++run_.counters->droppedMessages;
            return;
        }
        const Slot& newest = *slots_[current_];
        if (!newest.begun || r.frame > newest.frame.frame) {
            if (early_.size() < kMaxEarlyTiles) early_.push_back(std::move(msg));
            return;
        }
        Slot* slot = slotOf(r.frame);
        if (!slot) return;  // stale
        FrameAssembler& assembly = slot->assembly;
        TileRect rect;
        TileView view;
        if (assembly.claim(r.frame, r.tile, rect, view) != FrameAssembler::Claim::Granted) return;
        try {
            if (r.format != slot->frame.pixels) throw DecodeError("a tile in another pixel format than its frame's");
            if (r.depth.empty() == slot->frame.depth)
                throw DecodeError(slot->frame.depth ? "a tile without the depth its frame asks for" : "a tile with depth");
            const uint8_t features = slot->frame.denoise ? slot->frame.denoise->features : 0;
            if (r.features.empty() == (features != 0))
                throw DecodeError(features ? "a tile without the features its frame asks for" : "a tile with features");
            if (r.format == TilePixels::LinearHalf) {
                // An accumulated frame's tile: into the view's linear image (what is summed) and
                // quantised into its 8-bit one, as the master does.
                float* linear = assembly.linearAt(assembly.viewOf(r.tile), rect.x0, rect.y0);
                const size_t stride = size_t(slot->frame.width) * 3;
                decodeWideTile(r.codec, r.pixels.data(), r.pixels.size(), rect.width(), rect.height(), linear, stride, scratch_);
                for (int y = 0; y < rect.height(); ++y)
                    linearToSrgb8(linear + size_t(y) * stride, size_t(rect.width()) * 3, view.data + y * view.stride);
            } else {
                decodeTile(r.codec, r.pixels.data(), r.pixels.size(), rect.width(), rect.height(), view.data, view.stride);
            }
            if (slot->frame.depth)
                decodeDepthTile(kDepthCodec, r.depth.data(), r.depth.size(), rect.width(), rect.height(),
                                assembly.depthAt(assembly.viewOf(r.tile), rect.x0, rect.y0), size_t(slot->frame.width),
                                scratch_);
            if (features)
                decodeFeatureTile(features, r.features.data(), r.features.size(), rect.width(), rect.height(),
                                  assembly.featuresAt(assembly.viewOf(r.tile), rect.x0, rect.y0), scratch_);
            assembly.commit(r.tile);
        } catch (const DecodeError& e) {
            assembly.release(r.tile);
            std::fprintf(stderr, "rtwall display: tile %u of frame %u did not decode: %s\n", r.tile, r.frame, e.what());
            return;
        }
        reportIfComplete();
    }

    // Frames are shown in order, one at a time: the next complete frame is made into what the
    // node shows (its running means go on) and reported only once the one before was swapped or
    // released without this node. The barrier releases frames in order, so waiting costs nothing,
    // and every frame held is presented.
    void reportIfComplete() {
        if (pendingSwap_) return;
        Slot* older = slots_[current_ ^ 1];
        Slot* newer = slots_[current_];
        for (Slot* slot : {older, newer}) {
            if (!slot->begun || slot->haveSent) continue;
            if (!slot->assembly.complete()) return;  // the newer waits for the older
            slot->haveSent = true;
            if (!reproject_) show(*slot);  // re-projecting: at its swap (keepSource), not before
            pendingSwap_ = slot->frame.frame;
            send(NodeHave{slot->frame.frame}, slot->frame.frame);
            return;
        }
    }

    // What the node shows of a frame it holds: made as the single-PC wall makes it. Re-projecting
    // (`source`), with each view's depth and held region, so that the frame becomes the newest
    // warp source and the one before it the older.
    struct Slot;
    EyeImages compose(const Slot& slot, bool source) {
        const NodeFrame& f = slot.frame;
        ComposeFrame c;
        c.views = f.views;
        c.eyes.assign(f.eyes.begin(), f.eyes.end());
        c.stochastic = f.stochastic;
        c.stateSeq = f.stateSeq;
        c.linear = slot.assembly.linear();
        if (slot.assembly.depth() && (source || f.denoise)) c.depth = slot.assembly.depthImages();
        c.keepForWarp = source;
        if (source) c.held = slot.held;
        if (f.denoise) {
            // As the single-PC wall filters the frame (its screens, each with its ring).
            c.denoise = f.denoise->settings;
            c.features = slot.assembly.featureImages();
            c.sceneSeq = f.denoise->sceneSeq;
            if (f.views.empty()) c.camera = f.denoise->camera;
            c.denoiseWindows = slot.windows;
            c.denoiseRing = f.denoise->ring;
        }
        EyeImages out = compositor_.compose(c, slot.assembly.images(), slot.assembly.linearImages());
        // Each view's depth beside its image, for a warp on the node (issue 27).
        if (run_.depth && slot.assembly.depth()) run_.depth(f.frame, slot.assembly.depthImages());
        return out;
    }
    void show(const Slot& slot) { shown_ = compose(slot, false); }

    // Re-projecting: the released frame becomes the newest warp source (accumulated and composed
    // as show() does); the frame before stays the older one.
    void keepSource(const Slot& slot, const std::vector<std::string>& leftOut) {
        const NodeFrame& f = slot.frame;
        onScreen_ = compose(slot, true);
        onScreenFrame_ = f.frame;
        sourceFrame_ = f.frame;
        leftOut_ = leftOut;
    }

    // A refresh: the newest source warped to the master's pose, shown at once, and answered.
    std::optional<int> onPose(const NodePose& pose) {
        if (!reproject_) {
            if (run_.counters) ++run_.counters->droppedMessages;
            std::fprintf(stderr, "rtwall display: dropped a pose from the master: this wall does not re-project\n");
            return std::nullopt;
        }
        if (compositor_.reprojectViews() == 0 || pose.cameras.size() != compositor_.reprojectViews()) {
            // No frame with depth yet, or a pose for other views than the frame held (the views
            // changed while this node was left out): the screens keep what they show.
            if (run_.counters) ++run_.counters->skippedPoses;
            if (compositor_.reprojectViews() != 0 && !saidMismatch_) {
                std::fprintf(stderr, "rtwall display: a pose of %zu cameras for a frame of %zu views is not shown\n",
                             pose.cameras.size(), compositor_.reprojectViews());
                saidMismatch_ = true;
            }
            return std::nullopt;
        }
        NodeRefresh r;
        r.refresh = pose.refresh;
        r.frame = sourceFrame_;
        r.compositor = &compositor_;
        r.targets = pose.cameras;
        r.debug = pose.debug;
        r.leftOut = &leftOut_;
        if (run_.roomEyes && pose.roomEyes) run_.roomEyes(*pose.roomEyes);
        if (run_.refresh) {
            run_.refresh(r);
        } else if (run_.present) {
            const EyeImages& eyes = compositor_.reproject(pose.cameras, {}, pose.debug);
            run_.present(sourceFrame_, &eyes.left, eyes.right.rgb.empty() ? nullptr : &eyes.right, leftOut_);
        }
        send(NodeShown{pose.refresh}, sourceFrame_);
        if (run_.counters) ++run_.counters->refreshes;
        if (sourceFrame_ > lastCounted_) {
            lastCounted_ = sourceFrame_;
            if (run_.frames > 0 && ++presented_ >= run_.frames) {
                send(Goodbye{"display node '" + run_.name + "' presented its frames"});
                return 0;
            }
        }
        return std::nullopt;
    }

    // The operator console's picture (issue 31): the cells of the pixels this node owns of the
    // frame it presented last, each eye's rows with any in bands of at most
    // kMaxPreviewPartBytes, then an empty last part. Nothing presented yet (or no owners
    // function): one part of frame 0.
    void onPreviewAsk(const NodePreviewAsk& ask) {
        NodePreview part;
        part.id = ask.id;
        part.last = true;
        const Image* eyes[2] = {&onScreen_.left, onScreen_.right.rgb.empty() ? nullptr : &onScreen_.right};
        const bool asked = (ask.nodes >> index_) & 1;  // else it owns no pixel: only the last part
        if (onScreenFrame_ == 0 || !run_.previewOwners || onScreen_.left.rgb.empty()) {
            send(part);
            return;
        }
        part.frame = onScreenFrame_;
        part.srcWidth = onScreen_.left.width;
        part.srcHeight = onScreen_.left.height;
        for (int e = 0; e < 2 && asked; ++e) {
            if (!eyes[e]) continue;
            const Image& im = *eyes[e];
            BoxGrid grid;
            try {
                grid = boxGrid(im.width, im.height, ask.width);
            } catch (const std::invalid_argument& err) {
                std::fprintf(stderr, "rtwall display: no picture for the console: %s\n", err.what());
                break;
            }
            const std::vector<uint8_t>& owners = ownersOf(im.width, im.height, e, ask.nodes);
            if (owners.size() != size_t(im.width) * size_t(im.height)) break;  // said by ownersOf
            sums_.assign(grid.cells() * 4, 0);
            addBoxSums(im, grid, owners.data(), uint8_t(index_), sums_.data());
            // The bounding box of the cells with pixels of this node.
            int x0 = grid.width, y0 = grid.height, x1 = 0, y1 = 0;
            uint32_t largest = 0;
            for (int y = 0; y < grid.height; ++y)
                for (int x = 0; x < grid.width; ++x) {
                    const uint32_t* c = sums_.data() + (size_t(y) * grid.width + x) * 4;
                    if (c[3] == 0) continue;
                    x0 = std::min(x0, x), x1 = std::max(x1, x + 1), y0 = std::min(y0, y), y1 = std::max(y1, y + 1);
                    largest = std::max({largest, c[0], c[1], c[2], c[3]});
                }
            if (x1 <= x0) continue;
            const int valueBytes = previewValueBytes(largest);
            const size_t rowBytes = size_t(x1 - x0) * 4 * size_t(valueBytes);
            const int band = int(std::max<size_t>(1, kMaxPreviewPartBytes / rowBytes));
            for (int y = y0; y < y1; y += band) {
                const int yEnd = std::min(y1, y + band);
                band_.clear();
                for (int row = y; row < yEnd; ++row) {
                    const uint32_t* from = sums_.data() + (size_t(row) * grid.width + x0) * 4;
                    band_.insert(band_.end(), from, from + size_t(x1 - x0) * 4);
                }
                NodePreview p = part;
                p.eye = uint8_t(e);
                p.x0 = x0, p.x1 = x1, p.y0 = y, p.y1 = yEnd;
                p.valueBytes = uint8_t(valueBytes);
                p.last = false;
                encodePreviewCells(band_.data(), band_.size() / 4, valueBytes, p.cells, scratch_);
                send(p, onScreenFrame_);
            }
        }
        send(part, onScreenFrame_);
    }

    // Who owns each pixel (DisplayNodeRun::previewOwners), kept while the frame size and the
    // nodes asked stay the same.
    const std::vector<uint8_t>& ownersOf(int width, int height, int eye, uint64_t nodes) {
        OwnersKey key{width, height, nodes};
        OwnersCache& cache = owners_[eye];
        if (!(cache.key == key)) {
            try {
                cache.owners = run_.previewOwners(width, height, eye, nodes);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "rtwall display: no picture for the console: %s\n", e.what());
                cache.owners.clear();
            }
            if (!cache.owners.empty() && cache.owners.size() != size_t(width) * size_t(height)) {
                std::fprintf(stderr, "rtwall display: no picture for the console: %zu pixel owners for a %dx%d frame\n",
                             cache.owners.size(), width, height);
                cache.owners.clear();
            }
            cache.key = key;
        }
        return cache.owners;
    }

    // The slot that holds `frame` (begun in this session), if any.
    Slot* slotOf(uint32_t frame) {
        for (Slot& slot : store_)
            if (slot.begun && slot.frame.frame == frame) return &slot;
        return nullptr;
    }

    // Handshake events of the connection to the master: a refusal is said, not just "no master".
    void readMonitor() {
        monitor_.read(16, [&](const MonitorEvent& e) {
            handshakes_.onEvent(e, run_.connect, keys_.publicKey, run_.counters ? &run_.counters->refusedHandshakes : nullptr,
                                run_.counters ? &run_.counters->failedHandshakes : nullptr);
        });
    }

    const DisplayNodeRun& run_;
    KeyPair keys_, tileKeys_;  // with CURVE: this node's pair towards the master, and its tile socket's
    std::string serverKey_;    // the master's public key
    zmq::context_t ctx_{1};
    zmq::socket_t master_;
    SocketMonitor monitor_;  // handshake events of master_
    uint64_t monitorSeq_ = 0;
    MasterHandshakeWatch handshakes_{"node", "rtwall display"};  // said once until it changes
    std::unique_ptr<ZapHandler> zap_;  // with CURVE: the tile socket's key check (goes after the socket)
    zmq::socket_t tiles_{ctx_, zmq::socket_type::router};
    std::string endpoint_;
    uint64_t session_ = 0;
    uint32_t index_ = 0;
    int heartbeatMs_ = 250, timeoutMs_ = 3000;
    double lastHeard_ = 0, lastSent_ = 0;
    std::map<uint32_t, std::vector<uint64_t>> routes_;  // tile masks by their first frame
    // The newest frame (slots_[current_]) and the one before it.
    struct Slot {
        FrameAssembler assembly;
        NodeFrame frame;        // what assembly holds
        bool begun = false;     // holds a frame begun in this session and not yet swapped
        bool haveSent = false;  // shown and reported (NodeHave)
        std::vector<TileRect> held;  // per view: the bounding box of the tiles routed to this node
        std::vector<std::vector<TileRect>> windows;  // per view: the denoise windows this node shows
    };
    Slot store_[3];
    Slot* slots_[2] = {&store_[0], &store_[1]};
    Slot* parked_ = &store_[2];  // re-projecting: a reported frame overtaken by two newer ones, until its swap
    int current_ = 0;
    Compositor compositor_;                // the running means go on from frame to frame
    EyeImages shown_;                      // what the node shows of the last frame it held
    EyeImages onScreen_;                   // what it presented at the last swap it held (the console's picture)
    uint32_t onScreenFrame_ = 0;           // onScreen_'s frame; 0: none yet
    struct OwnersKey {
        int width = 0, height = 0;
        uint64_t nodes = 0;
        bool operator==(const OwnersKey&) const = default;
    };
    struct OwnersCache {
        OwnersKey key;
        std::vector<uint8_t> owners;
    } owners_[2];
    std::vector<uint32_t> sums_, band_;    // a picture's cells, reused
    std::optional<uint32_t> pendingSwap_;  // shown_'s frame, reported and not yet swapped
    // Re-projection (the welcome's flag): the compositor's newest source is sourceFrame_, released
    // with leftOut_ left out; lastCounted_ is the newest frame counted as presented (run_.frames).
    bool reproject_ = false;
    uint32_t sourceFrame_ = 0, lastCounted_ = 0;
    std::vector<std::string> leftOut_;
    bool saidMismatch_ = false;
    bool saidWindows_ = false;  // a wall whose windows could not be made was said once
    std::vector<zmq::message_t> early_;
    std::vector<uint8_t> scratch_;
    int presented_ = 0;
};

}  // namespace

std::string advertisedNodeEndpoint(const std::string& bound, const std::string& advertise) {
    const size_t colon = bound.rfind(':');
    if (!bound.starts_with("tcp://") || colon == std::string::npos || colon < 6)
        throw InputError("display node: cannot tell the clients where '" + bound + "' is (expected tcp://HOST:PORT)");
    const std::string host = bound.substr(6, colon - 6), port = bound.substr(colon + 1);
    if (advertise.empty()) {
        if (host == "0.0.0.0" || host == "*" || host == "[::]" || host == "::" || host == "[*]")
            throw InputError("display node: --bind " + bound + " listens on every address: say which one the render "
                             "clients reach this node at (--advertise HOST)");
        return bound;
    }
    bool ok = !advertise.empty() && advertise.size() <= 240;
    if (ok && advertise.front() == '[') {
        // A bracketed IPv6 address.
        ok = advertise.size() > 2 && advertise.back() == ']';
        for (size_t i = 1; ok && i + 1 < advertise.size(); ++i) {
            const char c = advertise[i];
            ok = std::isxdigit(static_cast<unsigned char>(c)) || c == ':' || c == '.';
        }
    } else {
        for (char c : advertise) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-');
        ok = ok && advertise.front() != '-' && advertise.front() != '.';
    }
    if (!ok)
        throw InputError("display node: --advertise '" + advertise +
                         "' is not a host name, an IPv4 address or a bracketed IPv6 address ([::1])");
    if (advertise == "0.0.0.0" || advertise == "[::]")
        throw InputError("display node: --advertise " + advertise + " is not an address the clients can reach");
    return "tcp://" + advertise + ":" + port;
}

int runDisplayNode(const DisplayNodeRun& run) {
    if (run.name.empty()) throw InputError("display node: no name (--node NAME)");
    DisplayNode node(run);
    return node();
}

}  // namespace rtwall
