// The attacker of issue 16: everything a peer on the master's port can send, at a steady rate,
// for a bounded time. Each message is counted by the kind the master must file it under, so a
// test can check that nothing the master dropped went uncounted.
#include "adversary.h"

#include "codec.h"
#include "net.h"
#include "protocol.h"
#include "security.h"

#include <zmq.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <optional>
#include <random>
#include <thread>

namespace rtwall::testing {

namespace {

using namespace cluster;
using Clock = std::chrono::steady_clock;

uint16_t portOf(const std::string& endpoint) {
    const size_t colon = endpoint.rfind(':');
    if (!endpoint.starts_with("tcp://127.") || colon == std::string::npos)
        throw InputError("attack: " + endpoint + " is not a loopback endpoint (tcp://127.x.x.x:PORT)");
    return uint16_t(std::stoi(endpoint.substr(colon + 1)));
}

// One well-formed message of every type, 1..kMaxMsgType, in a session.
std::vector<std::vector<uint8_t>> everyType(uint64_t session, uint32_t frame) {
    Header h;
    h.session = session;
    h.frame = frame;
    SceneSnapshot snap;
    snap.settings.width = 64;
    snap.settings.height = 48;
    Update update;
    update.seq = 7;
    update.baseSeq = 6;
    update.changes.push_back(LightChange{0, Light{}});
    TileResult result;
    result.frame = frame;
    result.tile = 1;
    result.codec = TileCodec::Raw;
    result.pixels.assign(48, 0x5A);
    std::vector<std::vector<uint8_t>> out;
    out.push_back(encodeMessage(h, Hello{kProtocolVersion, 1, "attacker"}));
    out.push_back(encodeMessage(h, Welcome{}));
    out.push_back(encodeMessage(h, snap));
    out.push_back(encodeMessage(h, MeshRequest{{1, 2}}));
    out.push_back(encodeMessage(h, MeshData{{1, 2}, {1, 2, 3}}));
    out.push_back(encodeMessage(h, update));
    out.push_back(encodeMessage(h, FrameBegin{frame, 3, TilePixels::Srgb8, {FrameView{}}}));
    out.push_back(encodeMessage(h, TileRequest{frame, 64}));
    out.push_back(encodeMessage(h, TileAssign{frame, {0, 1, 2}}));
    out.push_back(encodeMessage(h, result));
    out.push_back(encodeMessage(h, Heartbeat{frame, 3, true}));
    out.push_back(encodeMessage(h, Goodbye{"attacker"}));
    out.push_back(encodeMessage(h, Ready{3, {4, 5}}));
    out.push_back(encodeMessage(h, ResyncRequest{2}));
    out.push_back(encodeMessage(h, AssetRequest{{6, 7}}));
    out.push_back(encodeMessage(h, AssetData{{6, 7}, {1, 2, 3}}));
    out.push_back(encodeMessage(h, TileStalled{frame, 1, 5000}));
    out.push_back(encodeMessage(h, TileFailed{frame, 1, {0, 0, 8, 8}, 8, "attacker"}));
    // Display nodes (version 11). A node name no wall uses, and an endpoint on loopback: a master
    // that took this hello would still never send anyone anywhere else.
    out.push_back(encodeMessage(h, NodeHello{kProtocolVersion, "attacker", "tcp://127.0.0.1:9", ""}));
    out.push_back(encodeMessage(h, NodeWelcome{0, 250, 3000, "[wall]\n"}));
    out.push_back(encodeMessage(h, NodeFrame{frame, 64, 48, 16, TilePixels::Srgb8}));
    out.push_back(encodeMessage(h, NodeHave{frame}));
    out.push_back(encodeMessage(h, NodeSwap{frame, {"attacker"}}));
    out.push_back(encodeMessage(h, NodeSwapped{frame}));
    out.push_back(encodeMessage(h, NodeList{{{0, "attacker", "tcp://127.0.0.1:9", ""}}}));
    out.push_back(encodeMessage(h, TileRoutes{frame, {1, 1, 1}}));
    out.push_back(encodeMessage(h, TileDone{frame, 1, 100, 12}));
    out.push_back(encodeMessage(h, NodePose{frame, frame, true, {CameraDesc{}}}));
    out.push_back(encodeMessage(h, NodeShown{frame}));
    return out;
}

// A raw TCP connection to the port that sends junk and closes: random bytes (unversioned), or
// a ZMTP 3.0 greeting followed by a garbage command.
void rawJunk(uint16_t port, std::mt19937_64& rng, bool unversioned) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return;
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(port);
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
        std::vector<uint8_t> bytes;
        if (unversioned) {
            bytes.resize(1 + rng() % 2048);
            for (auto& b : bytes) b = uint8_t(rng());
        } else {
            bytes.assign(64, 0);
            bytes[0] = 0xFF;
            bytes[9] = 0x7F;
            bytes[10] = 3;
            const char* mech = rng() % 2 ? "NULL" : "CURVE";
            for (size_t i = 0; mech[i]; ++i) bytes[12 + i] = uint8_t(mech[i]);
            bytes.push_back(0x04);  // a short command frame
            bytes.push_back(uint8_t(8 + rng() % 200));
            for (int i = 0; i < 64; ++i) bytes.push_back(uint8_t(rng()));
        }
        (void)!send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    }
    close(fd);
}

class Attacker {
public:
    Attacker(const AttackOptions& o) : o_(o), port_(portOf(o.endpoint)), rng_(o.seed) {
        if (!o.serverKeyFile.empty()) serverKey_ = readPublicKey(o.serverKeyFile);
        samples_ = everyType(0x0BADC0DEull ^ rng_(), 1);
    }

    AttackReport run() {
        const auto start = Clock::now();
        const auto end = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o_.seconds));
        auto lastRaw = start, lastOversized = start, lastNewDealer = start;
        double owed = 0;
        auto last = start;
        newDealer();
        if (o_.join && !curve()) startMember();
        while (Clock::now() < end) {
            const auto now = Clock::now();
            owed += std::chrono::duration<double>(now - last).count() * o_.messagesPerSecond;
            last = now;
            for (; owed >= 1; owed -= 1) oneMessage();
            if (member_) pumpMember();
            if (now - lastRaw > std::chrono::milliseconds(50)) {
                lastRaw = now;
                const bool unversioned = o_.unversionedJunk && rng_() % 2;
                rawJunk(port_, rng_, unversioned);
                ++r_.rawConnections;
                r_.unversionedConnections += unversioned;
            }
            if (now - lastOversized > std::chrono::seconds(1)) {
                lastOversized = now;
                oversized();
            }
            // New peers now and then: messages from peers the master never saw, and (CURVE)
            // another refused handshake.
            if (now - lastNewDealer > std::chrono::milliseconds(500)) {
                lastNewDealer = now;
                newDealer();
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        // What is queued in the sockets still goes (linger), then the member leaves.
        dealer_.reset();
        member_.reset();
        return r_;
    }

private:
    bool curve() const { return !serverKey_.empty(); }

    std::unique_ptr<zmq::socket_t> socket() {
        auto s = std::make_unique<zmq::socket_t>(ctx_, zmq::socket_type::dealer);
        // What a socket took still goes after it is closed (a refused CURVE one never goes).
        s->set(zmq::sockopt::linger, curve() ? 0 : 5000);
        s->set(zmq::sockopt::sndhwm, 100000);
        if (curve()) {
            const KeyPair k = makeKeyPair();  // a key nobody listed
            s->set(zmq::sockopt::curve_serverkey, serverKey_);
            s->set(zmq::sockopt::curve_publickey, k.publicKey);
            s->set(zmq::sockopt::curve_secretkey, k.secretKey);
            ++r_.curveAttempts;
        }
        s->connect(o_.endpoint);
        return s;
    }

    void newDealer() {
        dealer_ = socket();
        sent_.clear();
    }

    // Counts only what the socket took; with CURVE nothing reaches the master's application.
    bool put(zmq::socket_t& s, const std::vector<uint8_t>& bytes, bool more = false) {
        const auto flags = more ? zmq::send_flags::sndmore | zmq::send_flags::dontwait : zmq::send_flags::dontwait;
        try {
            return s.send(zmq::const_buffer(bytes.data(), bytes.size()), flags).has_value();
        } catch (const zmq::error_t&) {
            return false;
        }
    }
    void tally(uint64_t AttackReport::*kind) {
        if (!curve()) ++(r_.*kind);
    }

    const std::vector<uint8_t>& sample() { return samples_[rng_() % samples_.size()]; }

    void oneMessage() {
        zmq::socket_t& s = *dealer_;
        switch (rng_() % 7) {
        case 0: {  // bytes that are not a message
            std::vector<uint8_t> junk(1 + rng_() % 200);
            for (auto& b : junk) b = uint8_t(rng_());
            if (put(s, junk)) tally(&AttackReport::malformed);
            break;
        }
        case 1: {  // a message of every type in several frames: [x, y], header and payload apart, a trailing frame
            const std::vector<uint8_t>& m = sample();
            std::vector<std::vector<uint8_t>> parts;
            switch (rng_() % 3) {
            case 0: parts = {{'x'}, {'y'}}; break;
            case 1: parts = {std::vector<uint8_t>(m.begin(), m.begin() + kHeaderSize), std::vector<uint8_t>(m.begin() + kHeaderSize, m.end())}; break;
            default: parts = {m, {}}; break;
            }
            if (parts[1].empty() && rng_() % 2) parts.push_back({'z'});
            bool ok = true;
            for (size_t i = 0; i < parts.size() && ok; ++i) ok = put(s, parts[i], i + 1 < parts.size());
            if (ok) tally(&AttackReport::malformed);
            break;
        }
        case 2: {  // truncated
            std::vector<uint8_t> m = sample();
            m.resize(m.size() - 1 - rng_() % (m.size() - 1));
            if (put(s, m)) tally(&AttackReport::malformed);
            break;
        }
        case 3: {  // a header that lies: magic, type, reserved field, length
            std::vector<uint8_t> m = sample();
            switch (rng_() % 4) {
            case 0: m[0] ^= 0x20; break;
            case 1: m[6] = uint8_t(kMaxMsgType + 1 + rng_() % 100); m[7] = 0; break;
            case 2: m[28] = 1; break;
            default: m.push_back(0); break;
            }
            if (put(s, m)) tally(&AttackReport::malformed);
            break;
        }
        case 4:
        case 5: {  // well-formed, of any type, from a peer that is no client; or one sent again
            if (rng_() % 3 == 0 && !sent_.empty()) {
                if (put(s, sent_[rng_() % sent_.size()])) tally(&AttackReport::unknownPeer);
                break;
            }
            std::vector<uint8_t> m = sample();
            if (MsgType(m[6]) == MsgType::Hello || MsgType(m[6]) == MsgType::NodeHello) {
                m[4] = uint8_t(kProtocolVersion + 1 + rng_() % 50);  // another protocol version: refused
                if (put(s, m)) tally(&AttackReport::refused);
                break;
            }
            if (put(s, m)) {
                tally(&AttackReport::unknownPeer);
                if (sent_.size() < 64) sent_.push_back(m);
            }
            break;
        }
        default:
            if (member_ && ready_) memberLies();
            break;
        }
    }

    // A message over the master's limit on a connection of its own: the transport drops it.
    void oversized() {
        auto s = socket();
        s->set(zmq::sockopt::linger, 200);
        std::vector<uint8_t> big(maxTileResultBytes() + (1 << 20), 0xAB);
        if (put(*s, big)) ++r_.oversized;
    }

    // ---- a client of the session that misbehaves -----------------------------------------

    void startMember() {
        member_ = std::make_unique<zmq::socket_t>(ctx_, zmq::socket_type::dealer);
        member_->set(zmq::sockopt::linger, 5000);
        member_->set(zmq::sockopt::sndhwm, 100000);
        member_->connect(o_.endpoint);
        Header h;
        put(*member_, encodeMessage(h, Hello{kProtocolVersion, 1, "attacker"}));
    }

    template <class Msg> std::vector<uint8_t> inSession(const Msg& m, uint32_t frame = 0) const {
        Header h;
        h.session = session_;
        h.frame = frame;
        return encodeMessage(h, m);
    }

    void pumpMember() {
        for (int i = 0; i < 64; ++i) {
            zmq::message_t msg;
            if (!member_->recv(msg, zmq::recv_flags::dontwait)) break;
            discardRestOf(*member_, msg);
            const auto* p = static_cast<const uint8_t*>(msg.data());
            try {
                const Header in = decodeHeader(p, msg.size());
                if (in.type == MsgType::Welcome) session_ = in.session;
                if (in.type == MsgType::FrameBegin) frame_ = decodeMessage<FrameBegin>(p, msg.size()).frame;
                if (in.type == MsgType::SceneSnapshot && !ready_) {
                    // Proves the state honestly once: from now on it is a client.
                    const SceneSnapshot snap = decodeMessage<SceneSnapshot>(p, msg.size());
                    if (!snap.meshes.empty()) mesh_ = snap.meshes.front().hash;
                    put(*member_, inSession(Ready{snap.updateSeq, stateHash(snap)}));
                    ready_ = true;
                    ++r_.joined;
                    if (mesh_) put(*member_, inSession(MeshRequest{*mesh_}));  // the one honest request
                }
            } catch (const DecodeError&) {
            }
        }
        if (session_ && Clock::now() - lastBeat_ > std::chrono::milliseconds(100)) {
            lastBeat_ = Clock::now();
            // A lying heartbeat: idle, having seen tiles nobody sent. It holds nothing, so it
            // can release nothing.
            put(*member_, inSession(Heartbeat{uint32_t(rng_()), uint32_t(rng_() % 100), true}));
        }
    }

    // Never accepted, each counted once by the master: stale (a frame that is not rendered),
    // repeated (a mesh asked for again) or unexpected (unknown files, master-only types, a
    // Ready for a state it was not sent).
    void memberLies() {
        zmq::socket_t& s = *member_;
        constexpr uint32_t kNoFrame = 0xFFFFFFF0u;
        std::vector<uint8_t> m;
        uint64_t AttackReport::*kind = &AttackReport::replayedOrUnexpected;
        switch (rng_() % 8) {
        case 0:
            m = inSession(TileRequest{kNoFrame, 8});
            kind = &AttackReport::stale;
            break;
        case 1: {
            TileResult r;
            r.frame = kNoFrame;
            r.tile = uint32_t(rng_() % 64);
            r.pixels.assign(12, 1);
            m = inSession(r, kNoFrame);
            kind = &AttackReport::stale;
            break;
        }
        case 2:
            m = inSession(TileStalled{kNoFrame, 0, 9999});
            kind = &AttackReport::stallReports;
            break;
        case 3: m = inSession(AssetRequest{{rng_(), rng_()}}); break;
        case 4: m = inSession(MeshRequest{{rng_(), rng_()}}); break;
        case 5:
            if (!mesh_) return;
            m = inSession(MeshRequest{*mesh_});
            break;
        case 6: m = inSession(Ready{uint32_t(rng_() % 5), {rng_(), rng_()}}); break;
        default: {
            // A message only the master sends.
            static constexpr MsgType kMasterOnly[] = {MsgType::Welcome,    MsgType::FrameBegin, MsgType::TileAssign,
                                                      MsgType::MeshData,   MsgType::AssetData,  MsgType::NodeWelcome,
                                                      MsgType::NodeFrame,  MsgType::NodeSwap,   MsgType::NodeList,
                                                      MsgType::TileRoutes};
            const MsgType t = kMasterOnly[rng_() % std::size(kMasterOnly)];
            for (const auto& sample : everyType(session_, frame_))
                if (MsgType(sample[6]) == t) m = sample;
            break;
        }
        }
        if (!put(s, m)) return;
        ++(r_.*kind);
        // ... and now and then the very same bytes again.
        if (rng_() % 2 == 0 && put(s, m)) ++(r_.*kind);
    }

    AttackOptions o_;
    uint16_t port_;
    std::mt19937_64 rng_;
    std::string serverKey_;
    zmq::context_t ctx_;
    std::unique_ptr<zmq::socket_t> dealer_, member_;
    std::vector<std::vector<uint8_t>> samples_, sent_;
    uint64_t session_ = 0;
    uint32_t frame_ = 0;
    bool ready_ = false;
    std::optional<Hash128> mesh_;
    Clock::time_point lastBeat_{};
    AttackReport r_;
};

}  // namespace

AttackReport attackMaster(const AttackOptions& options) {
    Attacker a(options);
    return a.run();
}

}  // namespace rtwall::testing
