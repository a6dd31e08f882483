// rtwall simulate (speed.h): the real tile scheduler against simulated clients and links, fed
// with a tile profile.
#include "speed.h"
#include "speed_util.h"

#include <algorithm>
#include <cstdio>

namespace rtwall::bench {

namespace {

// "100mbit", "1gbit", "10gbit", "2.5gbit", "800kbit", "0" or "unlimited" -> bits/s.
double parseRate(const std::string& text) {
    if (text == "0" || text == "unlimited") return 0;
    double v = 0;
    char unit[16] = {};
    if (std::sscanf(text.c_str(), "%lf%15s", &v, unit) < 1 || v <= 0)
        throw InputError("rate '" + text + "': expected e.g. 100mbit, 1gbit, 10gbit or unlimited");
    const std::string u(unit);
    if (u == "gbit") return v * 1e9;
    if (u == "mbit") return v * 1e6;
    if (u == "kbit") return v * 1e3;
    if (u == "bit" || u.empty()) return v;
    throw InputError("rate '" + text + "': unknown unit '" + u + "' (bit, kbit, mbit, gbit)");
}

// The simulation's configuration from the options (all but the client count).
SimConfig configOf(const SimulateOptions& o, const TileProfile& profile) {
    SimConfig cfg;
    if (!o.codec.empty()) {
        const CodecSettings want = parseCodec(o.codec);
        bool found = false;
        for (size_t i = 0; i < profile.codecs.size() && !found; ++i)
            if (codecLabel(profile.codecs[i].codec) == codecLabel(want)) {
                cfg.codec = i;
                found = true;
            }
        if (!found) throw InputError(o.profile + ": the profile has no codec '" + o.codec + "'");
    }
    cfg.threadsPerClient = o.threads;
    cfg.clientSpeed = o.clientSpeed;
    cfg.prefetch = o.prefetch;
    cfg.affinity = !o.noAffinity;
    cfg.stragglerFactor = o.straggler;
    cfg.clientLink = {parseRate(o.clientLink), o.latencyMs * 1e-3, o.spikeProb, o.spikeMs * 1e-3};
    cfg.masterBitsPerSecond = parseRate(o.masterLink);
    cfg.masterSecondsPerMessage = o.masterUs * 1e-6;
    cfg.decodeThreads = o.decodeThreads;
    cfg.decodeSpeed = o.decodeSpeed;
    cfg.messageOverheadBytes = uint32_t(o.overhead);
    cfg.frames = o.frames;
    cfg.seed = o.seed;
    cfg.hostCores = o.hostCores;
    cfg.hostBackgroundThreads = o.hostLoad;
    cfg.clientSecondsPerResult = o.clientUsPerResult * 1e-6;
    cfg.clientSecondsPerByte = o.clientNsPerByte * 1e-9;
    cfg.masterSecondsPerResult = o.masterUsPerResult * 1e-6;
    cfg.masterSecondsPerByte = o.masterNsPerByte * 1e-9;
    cfg.masterSecondsPerFrame = o.masterMsPerFrame * 1e-3;
    cfg.displayNodes = o.displayNodes;
    cfg.nodeBitsPerSecond = parseRate(o.nodeLink);
    cfg.nodeDecodeThreads = o.nodeDecodeThreads;
    return cfg;
}

}  // namespace

toml::table simulate(const SimulateOptions& o) {
    const TileProfile profile = readTileProfile(o.profile);
    SimConfig cfg = configOf(o, profile);
    double bytes = 0, render = 0;
    for (uint32_t b : profile.codecs[cfg.codec].bytes) bytes += b + o.overhead;
    for (double r : profile.renderSeconds.front()) render += r;
    toml::array rows;
    for (const std::string& n : splitList(o.clients)) {
        int clients = 0;
        if (std::sscanf(n.c_str(), "%d", &clients) != 1 || clients < 1 || clients > 100000)
            throw InputError("--clients: '" + n + "' is not a client count");
        cfg.clients = clients;
        const SimReport r = simulateCluster(profile, cfg);
        // The link-bound ceiling: results of one frame over the master's link, or over
        // all client links together, whichever is slower.
        // With display nodes the master's link carries only acks: the busiest node's link
        // instead, and the client links carry every copy of a tile shown by two nodes.
        double ceiling = 0;
        const double sent = cfg.displayNodes > 0 ? r.bytesPerFrame : bytes;
        if (cfg.displayNodes > 0) {
            const double busiest = *std::max_element(r.nodeBytesPerFrame.begin(), r.nodeBytesPerFrame.end());
            if (cfg.nodeBitsPerSecond > 0 && busiest > 0) ceiling = cfg.nodeBitsPerSecond / (8 * busiest);
        } else if (cfg.masterBitsPerSecond > 0) {
            ceiling = cfg.masterBitsPerSecond / (8 * bytes);
        }
        if (cfg.clientLink.bitsPerSecond > 0) {
            const double c = clients * cfg.clientLink.bitsPerSecond / (8 * sent);
            ceiling = ceiling > 0 ? std::min(ceiling, c) : c;
        }
        toml::table row{{"clients", clients},
                        {"fps", r.fps},
                        {"link_ceiling_fps", ceiling},
                        {"render_bound_fps", clients * o.threads * o.clientSpeed / render},
                        {"bytes_per_frame", r.bytesPerFrame},
                        {"master_link_load", r.masterLinkLoad},
                        {"max_client_link_load", r.maxClientLinkLoad},
                        {"master_cpu_load", r.masterCpuLoad},
                        {"mean_client_utilisation", r.meanUtilisation},
                        {"stolen_per_frame", r.stolenPerFrame},
                        {"reissued_per_frame", r.reissuedPerFrame},
                        {"affinity_hit_fraction", r.affinityHitFraction}};
        if (cfg.displayNodes > 0) {
            toml::array nodeBytes;
            for (double b : r.nodeBytesPerFrame) nodeBytes.push_back(b);
            row.insert("display_nodes", cfg.displayNodes);
            row.insert("node_bytes_per_frame", nodeBytes);
            row.insert("max_node_link_load", r.maxNodeLinkLoad);
            row.insert("mean_barrier_wait_ms", r.meanBarrierWait * 1e3);
            row.insert("mpixel_per_s", double(profile.width) * profile.height * r.fps * 1e-6);
        }
        if (o.text && cfg.displayNodes > 0)
            std::fprintf(o.text, "%4d clients, %d display nodes: %8.2f fps (link ceiling %8.2f), busiest node link %5.1f%%, "
                         "barrier wait %.2f ms\n",
                         clients, cfg.displayNodes, r.fps, ceiling, 100 * r.maxNodeLinkLoad, r.meanBarrierWait * 1e3);
        else if (o.text)
            std::fprintf(o.text, "%4d clients: %8.2f fps (link ceiling %8.2f), master link %5.1f%%, clients busy %5.1f%%, "
                         "%.1f stolen/frame\n",
                         clients, r.fps, ceiling, 100 * r.masterLinkLoad, 100 * r.meanUtilisation, r.stolenPerFrame);
        rows.push_back(std::move(row));
    }
    return toml::table{{"benchmark", "simulate"},      {"profile", o.profile},
                       {"codec", codecLabel(profile.codecs[cfg.codec].codec)},
                       {"client_link_bps", cfg.clientLink.bitsPerSecond},
                       {"master_link_bps", cfg.masterBitsPerSecond},
                       {"latency_ms", o.latencyMs},   {"prefetch", o.prefetch},
                       {"threads", o.threads},        {"affinity", !o.noAffinity},
                       {"display_nodes", o.displayNodes}, {"node_link_bps", cfg.nodeBitsPerSecond},
                       {"results", rows}};
}

}  // namespace rtwall::bench
