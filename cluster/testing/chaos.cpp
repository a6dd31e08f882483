// The chaos run of issue 16: real client processes frozen, killed, restarted and cut off at
// random (fixed seed) while the master renders; every frame must equal one machine's image of
// its state, and once the faults stop every frame must complete.
#include "adversary.h"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <random>
#include <thread>

extern char** environ;

namespace rtwall::testing {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

bool sh(const std::string& command) { return std::system((command + " >/dev/null 2>&1").c_str()) == 0; }

// Client namespaces on a bridge in a switch namespace of their own; the master (this process)
// reaches the bridge through a veth with the only address it binds. Cutting a client's link is
// taking its switch port down: no FIN, no RST, as a pulled cable.
class Namespaces {
public:
    Namespaces(int clients) : clients_(clients) {
        const int id = int(getpid() % 100000);
        tag_ = std::to_string(id);
        subnet_ = "10.197." + std::to_string(id % 250) + ".";
        down();
        ok_ = sh("ip netns add " + sw()) && sh("ip -n " + sw() + " link add br0 type bridge") &&
              sh("ip -n " + sw() + " link set br0 up") &&
              sh("ip link add " + hostPort() + " type veth peer name m0 netns " + sw()) &&
              sh("ip -n " + sw() + " link set m0 master br0 up") &&
              sh("ip addr add " + subnet_ + "1/24 dev " + hostPort()) && sh("ip link set " + hostPort() + " up");
        for (int i = 0; ok_ && i < clients; ++i)
            ok_ = sh("ip netns add " + ns(i)) && sh("ip link add " + port(i) + " type veth peer name eth0 netns " + ns(i)) &&
                  sh("ip link set " + port(i) + " netns " + sw()) && sh("ip -n " + sw() + " link set " + port(i) + " master br0 up") &&
                  sh("ip -n " + ns(i) + " addr add " + subnet_ + std::to_string(10 + i) + "/24 dev eth0") &&
                  sh("ip -n " + ns(i) + " link set eth0 up") && sh("ip -n " + ns(i) + " link set lo up");
    }
    ~Namespaces() { down(); }
    bool ok() const { return ok_; }
    std::string bind() const { return "tcp://" + subnet_ + "1:0"; }
    std::string ns(int i) const { return "rtwcc" + tag_ + "-" + std::to_string(i); }
    void cut(int i, bool cut) { sh("ip -n " + sw() + " link set " + port(i) + (cut ? " down" : " up")); }

private:
    std::string sw() const { return "rtwcs" + tag_; }
    std::string hostPort() const { return "rcm" + tag_; }
    std::string port(int i) const { return "rcp" + tag_ + "-" + std::to_string(i); }
    void down() {
        for (int i = 0; i < clients_; ++i) sh("ip netns del " + ns(i));
        sh("ip link del " + hostPort());
        sh("ip netns del " + sw());
    }
    int clients_;
    std::string tag_, subnet_;
    bool ok_ = false;
};

class ClientProcess {
public:
    ClientProcess(const std::filesystem::path& exe, const std::string& endpoint, const std::string& netns)
        : exe_(exe), endpoint_(endpoint), netns_(netns) {}
    ~ClientProcess() { kill(); }
    void start() {
        std::vector<std::string> args = {exe_.string(), "client", "--connect", endpoint_, "--threads", "1",
                                         "--exit-after-idle", "0", "--max-reconnect", "400"};
        if (!netns_.empty()) args.insert(args.begin(), {"ip", "netns", "exec", netns_});
        std::vector<char*> argv;
        for (auto& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        const std::string program = netns_.empty() ? exe_.string() : "/usr/sbin/ip";
        if (posix_spawn(&pid_, program.c_str(), nullptr, nullptr, argv.data(), environ) != 0) pid_ = -1;
    }
    void kill() {
        if (pid_ <= 0) return;
        ::kill(pid_, SIGCONT);
        ::kill(pid_, SIGKILL);
        waitpid(pid_, nullptr, 0);
        pid_ = -1;
    }
    void signal(int sig) {
        if (pid_ > 0) ::kill(pid_, sig);
    }

private:
    std::filesystem::path exe_;
    std::string endpoint_, netns_;
    pid_t pid_ = -1;
};

}  // namespace

ChaosReport runChaos(const SceneDesc& sceneIn, const ChaosOptions& o) {
    ChaosReport report;
    std::unique_ptr<Namespaces> net;
    if (o.linkCuts) {
        net = std::make_unique<Namespaces>(o.clients);
        if (!net->ok()) {
            report.error = "cannot make network namespaces here (root and iproute2 needed)";
            return report;
        }
    }
    // A few states, cycled frame by frame, and one machine's image of each.
    SceneDesc desc = sceneIn;
    constexpr int kStates = 3;
    std::vector<float> intensity;
    std::vector<Image> expected;
    for (int k = 0; k < kStates; ++k) {
        intensity.push_back(desc.lights.empty() ? 0.0f : desc.lights[0].intensity * (1.0f + 0.5f * float(k)));
        SceneDesc d = desc;
        if (!d.lights.empty()) d.lights[0].intensity = intensity.back();
        const Scene scene(d);
        expected.push_back(renderFrame(scene, Camera(d.cameras.front(), d.settings.width, d.settings.height), d.settings));
    }

    ClusterSettings cs;
    cs.async = false;
    cs.heartbeatMs = std::max(10, o.timeoutMs / 8);
    cs.timeoutMs = o.timeoutMs;
    if (net) {
        cs.bind = net->bind();
        cs.insecure = true;  // the run's own namespaces; nothing else can reach this address
    }
    Master master(desc, cs);
    std::atomic<bool> giveUp{false};
    master.setStopFlag(&giveUp);
    std::vector<std::unique_ptr<ClientProcess>> procs;
    for (int i = 0; i < o.clients; ++i) {
        procs.push_back(std::make_unique<ClientProcess>(o.exe, master.endpoint(), net ? net->ns(i) : std::string()));
        procs.back()->start();
    }
    if (!master.waitForClients(o.clients, 120'000)) {
        report.error = "the client processes did not join";
        return report;
    }

    // The monkey: one fault at a time per client, each undone after a random time.
    enum class State { Up, Stopped, Dead, Cut };
    struct Slot {
        State state = State::Up;
        Clock::time_point until;
    };
    std::vector<Slot> slots(size_t(o.clients));
    std::mutex reportMutex;
    std::atomic<bool> faultsOver{false};
    Clock::time_point lastUndo = Clock::now();
    auto undo = [&](size_t i) {
        switch (slots[i].state) {
        case State::Stopped: procs[i]->signal(SIGCONT); break;
        case State::Dead: procs[i]->start(); break;
        case State::Cut: net->cut(int(i), false); break;
        case State::Up: return;
        }
        slots[i].state = State::Up;
        lastUndo = Clock::now();
    };
    std::thread monkey([&] {
        std::mt19937_64 rng(o.seed);
        std::exponential_distribution<double> gap(1000.0 / std::max(1, o.faultIntervalMs));
        std::uniform_int_distribution<int> hold(100, std::max(101, o.faultMaxMs));
        auto after = [](double seconds) {
            return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
        };
        const auto end = after(o.seconds);
        auto next = after(gap(rng));
        while (Clock::now() < end && !giveUp) {
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
            const auto now = Clock::now();
            for (size_t i = 0; i < slots.size(); ++i)
                if (slots[i].state != State::Up && now >= slots[i].until) undo(i);
            if (now < next) continue;
            next = after(gap(rng));
            const size_t i = size_t(rng() % slots.size());
            if (slots[i].state != State::Up) continue;
            const int kinds = net ? 4 : 3;
            std::lock_guard lock(reportMutex);
            ++report.faults;
            switch (rng() % kinds) {
            case 0:
                procs[i]->signal(SIGSTOP);
                slots[i].state = State::Stopped;
                ++report.stops;
                break;
            case 1:
                procs[i]->kill();
                slots[i].state = State::Dead;
                ++report.kills;
                break;
            case 2:  // killed and started again at once (as systemd would)
                procs[i]->kill();
                procs[i]->start();
                ++report.restarts;
                lastUndo = now;
                continue;
            default:
                net->cut(int(i), true);
                slots[i].state = State::Cut;
                ++report.linkCuts;
                break;
            }
            slots[i].until = now + std::chrono::milliseconds(hold(rng));
        }
        for (size_t i = 0; i < slots.size(); ++i) undo(i);
        lastUndo = Clock::now();
        faultsOver = true;
    });
    // A frame that never completes ends the run (as a failure) instead of hanging it.
    std::atomic<double> frameStartedAt{0};
    std::atomic<bool> running{true};
    std::thread watchdog([&] {
        while (running) {
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
            const double s = frameStartedAt.load();
            if (s > 0 && std::chrono::duration<double>(Clock::now().time_since_epoch()).count() - s > o.frameGiveUpSeconds)
                giveUp = true;
        }
    });

    int after = 0;
    Clock::time_point overAt{};
    for (uint32_t f = 0; !giveUp; ++f) {
        const bool over = faultsOver.load();
        if (over && after == 0) overAt = lastUndo;
        if (over && after >= o.framesAfter) break;
        const int k = int(f % kStates);
        if (!desc.lights.empty()) {
            Light l = desc.lights[0];
            l.intensity = intensity[size_t(k)];
            master.setLight(0, l);
        }
        const auto t0 = Clock::now();
        frameStartedAt = std::chrono::duration<double>(t0.time_since_epoch()).count();
        try {
            const Image img = master.renderFrame();
            const double s = secondsSince(t0);
            std::lock_guard lock(reportMutex);
            ++report.frames;
            report.framesIdentical += img.rgb == expected[size_t(k)].rgb;
            if (over) {
                report.worstAfterLastFault = std::max(report.worstAfterLastFault, s);
                if (after == 0) report.firstFrameAfterLastFault = std::chrono::duration<double>(Clock::now() - overAt).count();
                ++after;
            } else {
                report.worstFrameSeconds = std::max(report.worstFrameSeconds, s);
            }
        } catch (const Cancelled&) {
            ++report.framesFailed;
            break;
        } catch (const std::exception& e) {
            // "no render client is connected" for a while: every client was down at once.
            ++report.framesFailed;
            if (over) break;
        }
        frameStartedAt = 0;
    }
    giveUp = true;
    running = false;
    monkey.join();
    watchdog.join();
    report.counters = master.counters();
    return report;
}

}  // namespace rtwall::testing
