// A stand-in master written by hand, to test what a client does with messages a real master
// never sends (a Welcome with another timeout, replays, asset bytes that are not the file's):
// a ZeroMQ ROUTER on loopback that receives and sends protocol messages one by one.
#pragma once

#include "protocol.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>
#include <zmq.hpp>

#include <chrono>
#include <functional>
#include <future>
#include <optional>
#include <string>
#include <vector>

namespace rtwall::test {

class FakeMaster {
public:
    FakeMaster() : router_(ctx_, zmq::socket_type::router) {
        router_.set(zmq::sockopt::linger, 0);
        router_.bind("tcp://127.0.0.1:0");
        endpoint = router_.get(zmq::sockopt::last_endpoint);
    }
    struct Received {
        std::string peer;
        cluster::Header header;
        std::vector<uint8_t> payload;
    };
    // The next message of the given type (others are skipped), within ms.
    std::optional<Received> expect(cluster::MsgType type, int ms) {
        const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
        while (std::chrono::steady_clock::now() < end) {
            zmq::pollitem_t item{router_.handle(), 0, ZMQ_POLLIN, 0};
            zmq::poll(&item, 1, std::chrono::milliseconds(10));
            zmq::message_t id, msg;
            if (!router_.recv(id, zmq::recv_flags::dontwait)) continue;
            if (!router_.recv(msg, zmq::recv_flags::dontwait)) continue;
            const auto* p = static_cast<const uint8_t*>(msg.data());
            Received r{id.to_string(), cluster::decodeHeader(p, msg.size()),
                       std::vector<uint8_t>(p + cluster::kHeaderSize, p + msg.size())};
            if (onOther && r.header.type != type) onOther(r);
            if (r.header.type == type) return r;
        }
        return std::nullopt;
    }
    template <class Msg> std::vector<uint8_t> send(const std::string& peer, const Msg& m, uint32_t frame = 0) {
        cluster::Header h;
        h.type = cluster::messageTypeOf(m);
        h.session = kSession;
        h.frame = frame;
        std::vector<uint8_t> bytes = cluster::encodeMessage(h, m);
        resend(peer, bytes);
        return bytes;
    }
    void resend(const std::string& peer, const std::vector<uint8_t>& bytes) {
        router_.send(zmq::buffer(peer), zmq::send_flags::sndmore);
        router_.send(zmq::buffer(bytes));
    }
    // One message of several frames (a hostile master).
    void sendParts(const std::string& peer, const std::vector<std::vector<uint8_t>>& parts) {
        router_.send(zmq::buffer(peer), zmq::send_flags::sndmore);
        for (size_t i = 0; i < parts.size(); ++i)
            router_.send(zmq::buffer(parts[i]), i + 1 < parts.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
    }
    static constexpr uint64_t kSession = 0xFACE;
    std::string endpoint;
    // Called with every message expect() skips (to answer mesh requests on the way, say).
    std::function<void(const Received&)> onOther;

private:
    zmq::context_t ctx_;
    zmq::socket_t router_;
};

// A scene as a master sends it: its snapshot, whose meshes[k] has the bytes meshBytes[k].
struct ScriptedScene {
    cluster::SceneSnapshot snapshot;
    std::vector<std::vector<uint8_t>> meshBytes;
};

inline ScriptedScene scriptedScene(const SceneDesc& desc) {
    ScriptedScene s;
    for (const MeshDesc& m : desc.meshes) {
        s.meshBytes.push_back(cluster::encodeMesh(*m.mesh));
        const std::vector<uint8_t>& bytes = s.meshBytes.back();
        s.snapshot.meshes.push_back({m.name, "shape:none", cluster::hashBytes(bytes.data(), bytes.size()), bytes.size()});
    }
    s.snapshot.materials = desc.materials;
    s.snapshot.instances = desc.instances;
    s.snapshot.lights = desc.lights;
    s.snapshot.settings = desc.settings;
    return s;
}

// Answers the client's request for each of the scene's meshes (10 s each). Fatal failures:
// call it in ASSERT_NO_FATAL_FAILURE.
inline void serveMeshes(FakeMaster& fake, const std::string& peer, const ScriptedScene& scene) {
    for (size_t i = 0; i < scene.meshBytes.size(); ++i) {
        const auto req = fake.expect(cluster::MsgType::MeshRequest, 10000);
        ASSERT_TRUE(req);
        const auto r = cluster::decodePayload<cluster::MeshRequest>(req->payload.data(), req->payload.size());
        for (size_t k = 0; k < scene.snapshot.meshes.size(); ++k)
            if (scene.snapshot.meshes[k].hash == r.hash) fake.send(peer, cluster::MeshData{r.hash, scene.meshBytes[k]});
    }
}

// A render client of `fake` on a thread of the test (one render thread) that gives up after
// `idleMs` without its master; `cs` may set more (counters, say). Its exit status comes back.
inline std::future<int> startClient(const FakeMaster& fake, int idleMs, ClientSettings cs = {}) {
    cs.connect = fake.endpoint;
    cs.threads = 1;
    cs.exitAfterIdleMs = idleMs;
    return std::async(std::launch::async, [cs] { return runClient(cs); });
}

// The client's Hello (within 10 s), answered with a Welcome that gives `peerTimeoutMs` as the
// master's peer timeout; `peer` names the client. Fatal failures: call it in ASSERT_NO_FATAL_FAILURE.
inline void welcome(FakeMaster& fake, std::string& peer, uint32_t peerTimeoutMs = 3000) {
    const auto hello = fake.expect(cluster::MsgType::Hello, 10000);
    ASSERT_TRUE(hello);
    peer = hello->peer;
    fake.send(peer, cluster::Welcome{1, CodecSettings{}, 4, 100, peerTimeoutMs});
}

// The scene's snapshot sent to `peer` (its bytes kept in `sent`, for a replay), its meshes
// served and the client's Ready awaited (30 s). Fatal failures: call it in ASSERT_NO_FATAL_FAILURE.
inline void sendScene(FakeMaster& fake, const std::string& peer, const ScriptedScene& scene,
                      std::vector<uint8_t>* sent = nullptr) {
    const std::vector<uint8_t> bytes = fake.send(peer, scene.snapshot);
    if (sent) *sent = bytes;
    ASSERT_NO_FATAL_FAILURE(serveMeshes(fake, peer, scene));
    ASSERT_TRUE(fake.expect(cluster::MsgType::Ready, 30000));
}

// A frame's one view, of d's first camera (protocol 13 sends views with FrameBegin).
inline std::vector<FrameView> oneView(const SceneDesc& d) { return {FrameView{d.cameras.front(), {}, 0, 0}}; }

}  // namespace rtwall::test
