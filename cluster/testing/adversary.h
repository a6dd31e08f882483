// Test helpers for the cluster (issue 16), shared by the tests and `rtwall bench attack|chaos`:
// an attacker that throws everything a peer can send at a running master, and a chaos run
// that freezes, kills and restarts render clients (and cuts their links) while frames render.
// Not part of the product: a library of the tests, as OSPRay's ospray_testing is.
#pragma once

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace rtwall::testing {

struct AttackOptions {
    std::string endpoint;                 // the master, tcp://127.0.0.1:PORT (loopback only)
    std::filesystem::path serverKeyFile;  // a CURVE master: its public key (the attacker's own keys are not allowed)
    double seconds = 3.0;
    int messagesPerSecond = 2000;         // app-level messages, all kinds together
    uint64_t seed = 1;
    // Also join as a client (Hello, proof of the state) and misbehave inside the session:
    // repeats, stale and unexpected messages, results that do not decode, lying heartbeats.
    // Without CURVE anyone local can do this; with CURVE the handshake keeps it out.
    bool join = true;
    // Raw connections also send bytes that do not start like ZMTP 3: libzmq then falls back to
    // ZMTP 1.0 and, without CURVE, passes what it reads on as messages, a number of them that
    // only the bytes decide (the master counts them as malformed; this report cannot).
    bool unversionedJunk = true;
};

// What the attack sent, by the kind the master must count it as (MasterCounters). Only messages
// that reach the master's application count here; the transport drops the rest.
struct AttackReport {
    uint64_t malformed = 0;    // raw bytes, multi-frame messages of every type, truncated, bad header
    uint64_t unknownPeer = 0;  // well-formed messages of every type from a peer that is not a client
    uint64_t refused = 0;      // Hellos and NodeHellos of another protocol version
    // Inside a session (join), never accepted: requests and results for a frame that is not
    // rendered (stale); repeated or unknown mesh and file requests, a Ready for a state it was
    // not sent, types only the master sends (repeated or unexpected: which of the two for a
    // Ready depends on whether a state is on its way to it); and stall reports for tiles it
    // does not hold (counted as stalled tiles, not dropped: a stuck thread is news).
    uint64_t stale = 0;
    uint64_t replayedOrUnexpected = 0;
    uint64_t stallReports = 0;
    uint64_t joined = 0;          // sessions the attacker completed (Ready accepted)
    uint64_t rawConnections = 0;  // TCP connections that sent random bytes or a ZMTP greeting and garbage
    uint64_t unversionedConnections = 0;  // of which random bytes (see AttackOptions::unversionedJunk)
    uint64_t oversized = 0;       // messages over the master's size limit (the transport drops the connection)
    uint64_t curveAttempts = 0;   // connections with a key the master does not list (CURVE masters)
    uint64_t inSession() const { return stale + replayedOrUnexpected + stallReports; }
    uint64_t appMessages() const { return malformed + unknownPeer + refused + inSession(); }
};

// Attacks for `seconds` from this thread; returns what was sent. Bounded in time.
AttackReport attackMaster(const AttackOptions& options);

// A chaos run: `clients` render-client processes (the rtwall executable) and a master in this
// process render frames of `scene` for `seconds` while client processes are frozen (SIGSTOP, then
// SIGCONT), killed (SIGKILL, then started again), restarted, and (with link cuts) their network
// links cut and restored, at random with a fixed seed. The scene state changes every frame
// (cycling through a few light intensities), so lost updates and resyncs are exercised too.
// Then every fault is undone and `framesAfter` more frames render.
struct ChaosOptions {
    std::filesystem::path exe;  // the rtwall executable
    int clients = 4;
    double seconds = 10.0;
    uint64_t seed = 1;
    int faultIntervalMs = 300;  // mean time between faults
    int faultMaxMs = 1500;      // the longest a client stays frozen, dead or cut off
    bool linkCuts = false;      // clients in network namespaces of their own (root): cut their links too
    int framesAfter = 5;
    int timeoutMs = 400;        // the master's heartbeat timeout
    double frameGiveUpSeconds = 60;  // a frame taking longer counts as never completing
};

struct ChaosReport {
    uint64_t faults = 0, stops = 0, kills = 0, restarts = 0, linkCuts = 0;
    uint64_t frames = 0;           // completed
    uint64_t framesIdentical = 0;  // of which bit-identical to one machine's image of their state
    uint64_t framesFailed = 0;     // renderFrame gave up (no client for too long)
    double worstFrameSeconds = 0;  // during the faults
    double worstAfterLastFault = 0;     // frames rendered after every fault was undone
    double firstFrameAfterLastFault = 0;  // from the last fault's undoing to the first frame completed after it
    MasterCounters counters;
    std::string error;             // set when the run could not be set up (e.g. no namespaces)
};

ChaosReport runChaos(const SceneDesc& scene, const ChaosOptions& options);

}  // namespace rtwall::testing
