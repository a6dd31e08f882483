// rtwall bench cluster --display-nodes K (issue 19): a wall split over K display-node processes,
// render clients that send each tile straight to the nodes that show it, and the master that
// carries only control and a small ack per tile. The wall is generated here: a grid of screens
// whose columns go to the K nodes in equal runs (a 3840x2160 wall: 4 x 2 screens of 960x1080,
// a node per column, two or all four). Clients replay (each tile rendered once, then its bytes
// resent), nodes run headless and write nothing ([headless] write_every = 0), so a node's work
// is receiving, decoding and the barrier; the figures are the links' and the nodes', not the
// renderer's.
//
// Frames are paced by the swap: frame N+1 begins only when the barrier has released N (async
// off, Master::waitForSwap). A node assembles one frame at a time, and a client acknowledges a
// tile to the master as soon as it is queued for the node, so on a link slower than the master
// an unpaced master would begin frames whose predecessors are still on the wire.
#include "bench.h"
#include "bench_util.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>
#include <rtwall/process.h>
#include <rtwall/wall.h>

#include <toml++/toml.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
#include <thread>


namespace rtwall::bench {

namespace {

// CPU seconds (user + system, all threads) of a process so far; 0 once it is gone.
double processCpu(pid_t pid) {
    static const double tick = double(sysconf(_SC_CLK_TCK));
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string line;
    if (!std::getline(in, line)) return 0;
    const size_t close = line.rfind(')');
    if (close == std::string::npos) return 0;
    std::istringstream rest(line.substr(close + 2));
    std::vector<std::string> f;
    for (std::string x; rest >> x;) f.push_back(x);
    if (f.size() < 13) return 0;
    return (std::stod(f[11]) + std::stod(f[12])) / tick;  // utime, stime: fields 14 and 15 of proc(5)
}

// Busy time of all this machine's cores so far (every process and the kernel's softirqs, where
// shaped links and bridges do their work), in seconds; /proc/stat's first line.
double hostBusySeconds() {
    static const double tick = double(sysconf(_SC_CLK_TCK));
    std::ifstream in("/proc/stat");
    std::string cpu;
    double user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
    in >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal;
    return (user + nice + system + irq + softirq + steal) / tick;
}

// `rtwall display --headless` processes, node i in network namespace <netns><i> when given,
// binding its tile socket on addresses[i]. Stopped (SIGTERM, SIGKILL after 2 s) on destruction.
class NodeProcesses {
public:
    NodeProcesses(const std::vector<std::string>& names, const std::string& endpoint, const std::vector<std::string>& addresses,
                  const std::string& netns, const std::filesystem::path& out) {
        std::error_code ec;
        const std::string self = std::filesystem::canonical("/proc/self/exe", ec).string();
        for (size_t i = 0; i < names.size(); ++i) {
            std::vector<std::string> args = {self, "display", "--connect", endpoint, "--node", names[i], "--headless",
                                             "--out", (out / names[i]).string(), "--bind", "tcp://" + addresses[i] + ":0",
                                             "--exit-after-idle", "5000"};
            std::string program = self;
            if (!netns.empty()) {
                args.insert(args.begin(), {"ip", "netns", "exec", netns + std::to_string(i + 1)});
                program = "/usr/sbin/ip";
            }
            int pid = -1;
            const int err = spawnProcess(program, args, pid);
            if (err != 0) throw InputError(std::string("cannot start a display node process: ") + std::strerror(err));
            pids_.push_back(pid);
        }
    }
    ~NodeProcesses() { endProcesses(pids_, 2000); }
    NodeProcesses(const NodeProcesses&) = delete;
    NodeProcesses& operator=(const NodeProcesses&) = delete;
    const std::vector<int>& pids() const { return pids_; }

private:
    std::vector<int> pids_;
};

// The grid's column count: 4 (or K when K does not divide 4, or a multiple of both), so that
// each node drives an equal run of whole columns.
int gridColumns(int nodes) { return std::lcm(nodes, 4); }

}  // namespace

std::string nodeBenchWall(int width, int height, int nodes) {
    if (nodes < 1 || size_t(nodes) > kMaxDisplayNodes)
        throw InputError("--display-nodes " + std::to_string(nodes) + ": expected 1 to " + std::to_string(kMaxDisplayNodes));
    const int columns = gridColumns(nodes), rows = height % 2 == 0 ? 2 : 1;
    if (columns > 64 || width % columns != 0)
        throw InputError("--display-nodes " + std::to_string(nodes) + ": a " + std::to_string(width) +
                         "-pixel wide wall does not split into " + std::to_string(columns) + " equal screen columns");
    std::ostringstream w;
    w << "# rtwall bench cluster --display-nodes " << nodes << "\n[wall]\nname = \"bench " << nodes
      << " nodes\"\nvsync = false\n\n[grid]\ncolumns = " << columns << "\nrows = " << rows
      << "\nscreen_width = " << width / columns << "\nscreen_height = " << height / rows << "\n";
    const int per = columns / nodes;
    for (int n = 0; n < nodes; ++n)
        w << "\n[[node]]\nname = \"n" << n + 1 << "\"\ncolumns = [" << n * per << ", " << (n + 1) * per - 1 << "]\n";
    w << "\n[headless]\nwrite_every = 0\n";
    return w.str();
}

namespace {

// What each node receives per frame: encoded bytes and pixels of its tiles, from the routing the
// master uses and each tile encoded once here (message headers not counted).
struct NodeLoad {
    std::vector<double> bytes, pixels;
    size_t fanOutTiles = 0;  // tiles that go to more than one node
};

NodeLoad nodeLoad(const DisplayNodeSettings& dn, const Image& frame, int tileSize, const CodecSettings& codec) {
    const std::vector<TileRect> tiles = makeTiles(frame.width, frame.height, tileSize);
    const std::vector<uint64_t> masks = dn.routes(frame.width, frame.height, tileSize, {});
    NodeLoad load;
    load.bytes.assign(dn.names.size(), 0.0);
    load.pixels.assign(dn.names.size(), 0.0);
    for (size_t t = 0; t < tiles.size(); ++t) {
        const TileRect& r = tiles[t];
        Image crop{r.width(), r.height(), std::vector<uint8_t>(size_t(r.width()) * r.height() * 3)};
        for (int y = 0; y < r.height(); ++y)
            std::memcpy(crop.rgb.data() + size_t(y) * r.width() * 3, frame.rgb.data() + (size_t(r.y0 + y) * frame.width + r.x0) * 3,
                        size_t(r.width()) * 3);
        uint64_t bytes = 0;
        codecRoundTrip(crop, tileSize, codec, &bytes);
        if (std::popcount(masks[t]) > 1) ++load.fanOutTiles;
        for (size_t n = 0; n < dn.names.size(); ++n)
            if (masks[t] >> n & 1) {
                load.bytes[n] += double(bytes);
                load.pixels[n] += double(r.width()) * r.height();
            }
    }
    return load;
}

toml::array arrayOf(const std::vector<double>& v, double scale = 1.0) {
    toml::array a;
    for (double x : v) a.push_back(x * scale);
    return a;
}

// One node count and codec: master, K node processes, the clients; warmed up, then o.frames
// frames, each begun when the previous one has been swapped.
toml::table measureNodes(const SceneDesc& desc, const Image& frame, int nodes, const std::string& codecName,
                         const ClusterOptions& o) {
    const std::string text = nodeBenchWall(o.width, o.height, nodes);
    const WallConfig wall = parseWallConfig(text, "the benchmark's wall");
    ClusterSettings cs;
    cs.prefetch = o.nodePrefetch;
    cs.codec.codec = tileCodecFromName(codecName);
    cs.async = false;  // paced by the swap (see the top of this file)
    cs.bind = o.bind;
    cs.insecure = o.insecure;
    cs.displayNodes = displayNodeSettings(wall, text);
    const NodeLoad load = nodeLoad(cs.displayNodes, frame, o.tile, cs.codec);

    std::vector<std::string> addresses = o.nodeAddresses;
    if (addresses.empty()) addresses.assign(size_t(nodes), "127.0.0.1");
    const std::filesystem::path out = std::filesystem::temp_directory_path() / ("rtwall-bench-nodes-" + std::to_string(getpid()));
    struct RemoveAfter {
        std::filesystem::path dir;
        ~RemoveAfter() {
            std::error_code ec;
            std::filesystem::remove_all(dir, ec);
        }
    } cleanup{out};

    Master master(desc, cs);
    NodeProcesses nodeProcs(cs.displayNodes.names, master.endpoint(), addresses, o.nodeNetns, out);
    LocalClients clients(o.maxClients, master.endpoint(), 1, !o.render, o.netns);
    if (!master.waitForClients(o.maxClients, 120'000)) throw InputError("local clients did not join");
    // Until every node has joined and swapped a frame, then two warm-up frames (replay caches).
    FrameReport r;
    const Stopwatch joining;
    for (;;) {
        master.renderFrame(&r);
        if (r.displayNodes == size_t(nodes) && master.waitForSwap(r.frame, 5000)) break;
        if (joining.seconds() > 60)
            throw InputError("the display nodes did not all join and swap within 60 s (" + std::to_string(r.displayNodes) + " of " +
                             std::to_string(nodes) + " joined)");
    }
    for (int i = 0; i < 2; ++i) {
        master.renderFrame(&r);
        master.waitForSwap(r.frame, 10'000);
    }
    const uint64_t leftOutBefore = r.nodesLeftOut;
    auto cpuOf = [](const std::vector<pid_t>& pids) {
        std::vector<double> s;
        for (pid_t p : pids) s.push_back(processCpu(p));
        return s;
    };
    const double masterCpu0 = processCpu(getpid()), host0 = hostBusySeconds();
    const std::vector<double> clientCpu0 = cpuOf(clients.pids()), nodeCpu0 = cpuOf(nodeProcs.pids());
    std::vector<double> times, skews, bytes;
    const Stopwatch total;
    Stopwatch frameClock;
    for (int f = 0; f < o.frames; ++f) {
        master.renderFrame(&r);
        if (!master.waitForSwap(r.frame, 10'000))
            throw InputError("frame " + std::to_string(r.frame) + " was not swapped within 10 s");
        times.push_back(frameClock.seconds());
        frameClock.restart();
        bytes.push_back(double(r.bytes));
        // The report's skew is that of the newest frame every node had reported swapped when
        // this one's last tile was acknowledged: the previous frame's.
        if (f > 0 && nodes > 1) skews.push_back(r.lastSwapSkew);
    }
    const double wall_s = total.seconds();
    const double masterCpu = processCpu(getpid()) - masterCpu0, hostCores = (hostBusySeconds() - host0) / wall_s;
    std::vector<double> clientCpu = cpuOf(clients.pids()), nodeCpu = cpuOf(nodeProcs.pids());
    // One more frame, not timed: its report has the last measured frame's skew and left-outs.
    master.renderFrame(&r);
    if (nodes > 1) skews.push_back(r.lastSwapSkew);
    for (size_t i = 0; i < clientCpu.size(); ++i) clientCpu[i] = (clientCpu[i] - clientCpu0[i]) / wall_s;
    for (size_t i = 0; i < nodeCpu.size(); ++i) nodeCpu[i] = (nodeCpu[i] - nodeCpu0[i]) / wall_s;

    const double fps = o.frames / wall_s;
    const double pixels = std::accumulate(load.pixels.begin(), load.pixels.end(), 0.0);
    const double maxNodeBytes = *std::max_element(load.bytes.begin(), load.bytes.end());
    // The frame rate the node links allow: the busiest node's bytes over its link.
    const double linkBound = o.nodeLinkMbit > 0 ? o.nodeLinkMbit * 1e6 / 8 / maxNodeBytes : 0.0;
    const double skewMedian = skews.empty() ? 0.0 : median(skews);
    const double skewMax = skews.empty() ? 0.0 : *std::max_element(skews.begin(), skews.end());
    if (o.text) {
        std::fprintf(o.text, "nodes %d clients %d %-4s: %6.2f fps, %6.2f MB per node per frame (busiest), %7.1f Mpixel/s, "
                     "swap skew median %.3f ms max %.3f ms, %llu left out; CPU master %.2f",
                     nodes, o.maxClients, codecName.c_str(), fps, maxNodeBytes * 1e-6, pixels * fps * 1e-6, skewMedian * 1e3,
                     skewMax * 1e3, static_cast<unsigned long long>(r.nodesLeftOut - leftOutBefore), masterCpu / wall_s);
        for (double c : nodeCpu) std::fprintf(o.text, ", node %.2f", c);
        for (double c : clientCpu) std::fprintf(o.text, ", client %.2f", c);
        std::fprintf(o.text, "; all processes of the machine %.2f cores", hostCores);
        if (linkBound > 0) std::fprintf(o.text, "; %.0f%% of the node links' %.2f fps", 100 * fps / linkBound, linkBound);
        std::fprintf(o.text, "\n");
        std::fflush(o.text);
    }
    return toml::table{{"display_nodes", nodes},
                       {"clients", o.maxClients},
                       {"prefetch", o.nodePrefetch},
                       {"codec", codecName},
                       {"fps", fps},
                       {"median_frame_s", median(times)},
                       {"bytes_per_frame", median(bytes)},
                       {"node_bytes_per_frame", arrayOf(load.bytes)},
                       {"max_node_mb_per_frame", maxNodeBytes * 1e-6},
                       {"node_pixels_per_frame", arrayOf(load.pixels)},
                       {"fan_out_tiles", int64_t(load.fanOutTiles)},
                       {"mpixel_per_s", pixels * fps * 1e-6},
                       {"swap_skew_median_ms", skewMedian * 1e3},
                       {"swap_skew_max_ms", skewMax * 1e3},
                       {"nodes_left_out", int64_t(r.nodesLeftOut - leftOutBefore)},
                       {"node_link_mbit", o.nodeLinkMbit},
                       {"link_bound_fps", linkBound},
                       {"fraction_of_link_bound", linkBound > 0 ? fps / linkBound : 0.0},
                       {"cpu_cores", toml::table{{"master", masterCpu / wall_s},
                                                 {"nodes", arrayOf(nodeCpu)},
                                                 {"clients", arrayOf(clientCpu)},
                                                 {"host_busy", hostCores},
                                                 {"host_cores", double(std::thread::hardware_concurrency())}}}};
}

}  // namespace

toml::table clusterNodes(const SceneDesc& desc, const Image& reference, const ClusterOptions& o) {
    for (int k : o.displayNodes) nodeBenchWall(o.width, o.height, k);  // every count checked before the first run
    for (const std::string& c : o.nodeCodecs) tileCodecFromName(c);
    toml::array results;
    for (int k : o.displayNodes)
        for (const std::string& c : o.nodeCodecs) results.push_back(measureNodes(desc, reference, k, c, o));
    return toml::table{{"benchmark", "cluster-display-nodes"}, {"width", o.width}, {"height", o.height}, {"tile", o.tile},
                       {"frames", o.frames}, {"replay", !o.render}, {"link", o.link}, {"results", results}};
}

}  // namespace rtwall::bench
