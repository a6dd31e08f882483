// A DTrack frame to a wall session's tracker on loopback, for the session tests: sent, then
// waited for (2 s at most) until the session's tracker has counted `packets` datagrams.
#pragma once

#include <rtwall/tracking.h>
#include <rtwall/wall.h>

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

namespace rtwall::test {

inline void sendToSession(WallSession& s, const DTrackFrame& f, uint64_t packets) {
    DTrackSender(s.trackerPort()).send(f);
    for (int i = 0; i < 400; ++i) {
        const std::optional<TrackerState> st = s.tracker();
        if (st && st->packets >= packets) return;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ADD_FAILURE() << "the session's tracker did not get datagram " << packets;
}

// A head at room position (x, y, z) in millimetres, facing the wall, as datagram `frame` (the
// session's `frame`-th).
inline void sendHeadAt(WallSession& s, double x, double y, double z, uint64_t frame) {
    DTrackFrame f;
    f.frame = frame;
    DTrackBody b;
    b.quality = 1;
    b.position = {x, y, z};
    f.bodies.push_back(b);
    sendToSession(s, f, frame);
}

}  // namespace rtwall::test
