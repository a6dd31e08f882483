// netjitter: added delay, jitter and the reordering they cause, at the packet level, for a
// kernel without sch_netem. Packets sent to an NFQUEUE queue (iptables ... -j NFQUEUE
// --queue-num Q --queue-bypass) are held for base +- jitter ms (uniform) and then accepted, each
// on its own schedule, so a packet can overtake the one before it, as with netem's jitter.
// Root only, and only for namespaces a test or tools/netem.sh made; without the rule nothing
// reaches it, and with --queue-bypass traffic flows unchanged when it is not running.
//
//   netjitter --queue Q --delay MS --jitter MS [--report FILE]
//
// On SIGTERM or SIGINT it accepts what it still holds, writes `packets N reordered M` to FILE
// (or stdout) and exits. Reordered counts packets let go while an earlier one of the same
// direction (netfilter hook) was still held; flows are not told apart, so a packet overtaking
// another connection's counts too.
// <arpa/inet.h> before <linux/netfilter.h>: the other order defines struct in_addr twice.
#include <arpa/inet.h>
#include <libnetfilter_queue/libnetfilter_queue.h>
#include <linux/netfilter.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <string>

namespace {

using Clock = std::chrono::steady_clock;

volatile sig_atomic_t stopRequested = 0;
void onSignal(int) { stopRequested = 1; }

struct Held {
    uint32_t id;
    uint8_t hook;      // direction: NF_INET_LOCAL_IN, NF_INET_LOCAL_OUT, ...
    uint64_t arrival;  // arrival order
};

struct State {
    nfq_q_handle* queue = nullptr;
    std::mt19937_64 rng{std::random_device{}()};
    std::uniform_real_distribution<double> delay;
    std::multimap<Clock::time_point, Held> held;  // by release time
    uint64_t arrivals = 0, packets = 0, reordered = 0;
    std::map<uint8_t, std::set<uint64_t>> pendingArrivals;  // per direction: arrival numbers still held
};

int onPacket(nfq_q_handle*, nfgenmsg*, nfq_data* nfa, void* data) {
    auto& s = *static_cast<State*>(data);
    const nfqnl_msg_packet_hdr* ph = nfq_get_msg_packet_hdr(nfa);
    if (!ph) return 0;
    const double ms = std::max(0.0, s.delay(s.rng));
    const auto release = Clock::now() + std::chrono::microseconds(int64_t(ms * 1000));
    const uint64_t n = s.arrivals++;
    s.held.emplace(release, Held{ntohl(ph->packet_id), ph->hook, n});
    s.pendingArrivals[ph->hook].insert(n);
    return 0;
}

void release(State& s, Held h) {
    nfq_set_verdict(s.queue, h.id, NF_ACCEPT, 0, nullptr);
    ++s.packets;
    // Reordered: an earlier arrival in the same direction is still held when this one leaves.
    std::set<uint64_t>& pending = s.pendingArrivals[h.hook];
    if (!pending.empty() && *pending.begin() < h.arrival) ++s.reordered;
    pending.erase(h.arrival);
}

}  // namespace

int main(int argc, char** argv) {
    int queue = -1;
    double base = 0, jitter = 0;
    std::string report;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string k = argv[i];
        if (k == "--queue") queue = std::atoi(argv[i + 1]);
        else if (k == "--delay") base = std::atof(argv[i + 1]);
        else if (k == "--jitter") jitter = std::atof(argv[i + 1]);
        else if (k == "--report") report = argv[i + 1];
        else {
            std::fprintf(stderr, "netjitter: unknown option %s\n", k.c_str());
            return 2;
        }
    }
    if (queue < 0 || queue > 65535 || base < 0 || jitter < 0 || (argc - 1) % 2 != 0) {
        std::fprintf(stderr, "usage: netjitter --queue Q --delay MS --jitter MS [--report FILE]\n");
        return 2;
    }
    State s;
    s.delay = std::uniform_real_distribution<double>(base - jitter, base + jitter);
    nfq_handle* h = nfq_open();
    if (!h) {
        std::perror("netjitter: nfq_open");
        return 1;
    }
    s.queue = nfq_create_queue(h, uint16_t(queue), &onPacket, &s);
    if (!s.queue || nfq_set_mode(s.queue, NFQNL_COPY_META, 0) < 0) {
        std::fprintf(stderr, "netjitter: cannot bind queue %d (root? another program on it?)\n", queue);
        return 1;
    }
    nfq_set_queue_maxlen(s.queue, 65536);
    signal(SIGTERM, onSignal);
    signal(SIGINT, onSignal);
    std::printf("netjitter: queue %d, delay %.1f +- %.1f ms\n", queue, base, jitter);
    std::fflush(stdout);

    const int fd = nfq_fd(h);
    alignas(8) char buf[1 << 16];
    while (!stopRequested) {
        int waitMs = 50;
        if (!s.held.empty()) {
            const auto due = s.held.begin()->first - Clock::now();
            waitMs = int(std::max<int64_t>(0, std::chrono::duration_cast<std::chrono::milliseconds>(due).count()));
        }
        pollfd p{fd, POLLIN, 0};
        if (poll(&p, 1, waitMs) > 0 && (p.revents & POLLIN)) {
            for (int i = 0; i < 256; ++i) {
                const ssize_t n = recv(fd, buf, sizeof buf, MSG_DONTWAIT);
                if (n <= 0) break;
                nfq_handle_packet(h, buf, int(n));
            }
        }
        const auto now = Clock::now();
        while (!s.held.empty() && s.held.begin()->first <= now) {
            const Held held = s.held.begin()->second;
            s.held.erase(s.held.begin());
            release(s, held);
        }
    }
    for (const auto& [when, held] : s.held) release(s, held);
    nfq_destroy_queue(s.queue);
    nfq_close(h);
    FILE* out = report.empty() ? stdout : std::fopen(report.c_str(), "w");
    if (!out) return 1;
    std::fprintf(out, "packets %llu reordered %llu\n", (unsigned long long)s.packets, (unsigned long long)s.reordered);
    if (out != stdout) std::fclose(out);
    return 0;
}
