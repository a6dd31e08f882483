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
#include <optional>
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

// A few states, cycled frame by frame (the intensity of the first light, if any), and one
// machine's image of each.
struct ChaosStates {
    static constexpr int kCount = 3;
    std::optional<Light> light;
    std::vector<float> intensity;
    std::vector<Image> expected;
};

ChaosStates chaosStates(const SceneDesc& desc) {
    ChaosStates states;
    if (!desc.lights.empty()) states.light = desc.lights[0];
    for (int k = 0; k < ChaosStates::kCount; ++k) {
        states.intensity.push_back(desc.lights.empty() ? 0.0f : desc.lights[0].intensity * (1.0f + 0.5f * float(k)));
        SceneDesc d = desc;
        if (!d.lights.empty()) d.lights[0].intensity = states.intensity.back();
        const Scene scene(d);
        states.expected.push_back(renderFrame(scene, Camera(d.cameras.front(), d.settings.width, d.settings.height), d.settings));
    }
    return states;
}

// In-step frames with the run's timeout; with namespaces, bound to the address only they reach.
ClusterSettings chaosSettings(const ChaosOptions& o, const Namespaces* net) {
    ClusterSettings cs;
    cs.async = false;
    cs.heartbeatMs = std::max(10, o.timeoutMs / 8);
    cs.timeoutMs = o.timeoutMs;
    if (net) {
        cs.bind = net->bind();
        cs.insecure = true;  // the run's own namespaces; nothing else can reach this address
    }
    return cs;
}

Clock::time_point after(double seconds) {
    return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// What the three threads of a run share: the master renders frames, the monkey injects faults
// (one at a time per client, each undone after a random time), the watchdog gives up a frame
// that never completes.
class ChaosRun {
public:
    ChaosRun(const ChaosOptions& o, Namespaces* net, Master& master, ChaosReport& report)
        : o_(o), net_(net), master_(master), report_(report), slots_(size_t(o.clients)) {
        master_.setStopFlag(&giveUp_);
        for (int i = 0; i < o.clients; ++i) {
            procs_.push_back(std::make_unique<ClientProcess>(o.exe, master.endpoint(), net ? net->ns(i) : std::string()));
            procs_.back()->start();
        }
    }

    // The frames, each compared with its state's image, while the monkey and the watchdog run;
    // after the faults, o.framesAfter more.
    void run(const ChaosStates& states) {
        std::thread monkey([this] { injectFaults(); });
        std::thread watchdog([this] { watch(); });
        renderFrames(states);
        giveUp_ = true;
        running_ = false;
        monkey.join();
        watchdog.join();
    }

private:
    enum class State { Up, Stopped, Dead, Cut };
    struct Slot {
        State state = State::Up;
        Clock::time_point until;
    };

    void undo(size_t i) {
        switch (slots_[i].state) {
        case State::Stopped: procs_[i]->signal(SIGCONT); break;
        case State::Dead: procs_[i]->start(); break;
        case State::Cut: net_->cut(int(i), false); break;
        case State::Up: return;
        }
        slots_[i].state = State::Up;
        lastUndo_ = Clock::now();
    }

    // A fault of a random kind on client i (up); false for a restart, which has nothing to undo.
    bool fault(size_t i, Clock::time_point now, std::mt19937_64& rng) {
        const int kinds = net_ ? 4 : 3;
        std::lock_guard lock(reportMutex_);
        ++report_.faults;
        switch (rng() % kinds) {
        case 0:
            procs_[i]->signal(SIGSTOP);
            slots_[i].state = State::Stopped;
            ++report_.stops;
            return true;
        case 1:
            procs_[i]->kill();
            slots_[i].state = State::Dead;
            ++report_.kills;
            return true;
        case 2:  // killed and started again at once (as systemd would)
            procs_[i]->kill();
            procs_[i]->start();
            ++report_.restarts;
            lastUndo_ = now;
            return false;
        default:
            net_->cut(int(i), true);
            slots_[i].state = State::Cut;
            ++report_.linkCuts;
            return true;
        }
    }

    // The monkey's thread: faults at random gaps for o.seconds, then every fault undone.
    void injectFaults() {
        std::mt19937_64 rng(o_.seed);
        std::exponential_distribution<double> gap(1000.0 / std::max(1, o_.faultIntervalMs));
        std::uniform_int_distribution<int> hold(100, std::max(101, o_.faultMaxMs));
        const auto end = after(o_.seconds);
        auto next = after(gap(rng));
        while (Clock::now() < end && !giveUp_) {
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
            const auto now = Clock::now();
            for (size_t i = 0; i < slots_.size(); ++i)
                if (slots_[i].state != State::Up && now >= slots_[i].until) undo(i);
            if (now < next) continue;
            next = after(gap(rng));
            const size_t i = size_t(rng() % slots_.size());
            if (slots_[i].state != State::Up) continue;
            if (fault(i, now, rng)) slots_[i].until = now + std::chrono::milliseconds(hold(rng));
        }
        for (size_t i = 0; i < slots_.size(); ++i) undo(i);
        lastUndo_ = Clock::now();
        faultsOver_ = true;
    }

    // The watchdog's thread: a frame that never completes ends the run (as a failure) instead of
    // hanging it.
    void watch() {
        while (running_) {
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
            const double s = frameStartedAt_.load();
            if (s > 0 && std::chrono::duration<double>(Clock::now().time_since_epoch()).count() - s > o_.frameGiveUpSeconds)
                giveUp_ = true;
        }
    }

    void renderFrames(const ChaosStates& states) {
        int afterFaults = 0;
        Clock::time_point overAt{};
        for (uint32_t f = 0; !giveUp_; ++f) {
            const bool over = faultsOver_.load();
            if (over && afterFaults == 0) overAt = lastUndo_;
            if (over && afterFaults >= o_.framesAfter) break;
            const size_t k = f % ChaosStates::kCount;
            if (states.light) {
                Light l = *states.light;
                l.intensity = states.intensity[k];
                master_.setLight(0, l);
            }
            const auto t0 = Clock::now();
            frameStartedAt_ = std::chrono::duration<double>(t0.time_since_epoch()).count();
            try {
                const Image img = master_.renderFrame();
                const double s = secondsSince(t0);
                std::lock_guard lock(reportMutex_);
                ++report_.frames;
                report_.framesIdentical += img.rgb == states.expected[k].rgb;
                if (over) {
                    report_.worstAfterLastFault = std::max(report_.worstAfterLastFault, s);
                    if (afterFaults == 0) report_.firstFrameAfterLastFault = secondsSince(overAt);
                    ++afterFaults;
                } else {
                    report_.worstFrameSeconds = std::max(report_.worstFrameSeconds, s);
                }
            } catch (const Cancelled&) {
                ++report_.framesFailed;
                break;
            } catch (const std::exception& e) {
                // "no render client is connected" for a while: every client was down at once.
                ++report_.framesFailed;
                if (over) break;
            }
            frameStartedAt_ = 0;
        }
    }

    const ChaosOptions& o_;
    Namespaces* net_;
    Master& master_;
    ChaosReport& report_;
    std::vector<std::unique_ptr<ClientProcess>> procs_;
    std::vector<Slot> slots_;
    std::mutex reportMutex_;
    std::atomic<bool> giveUp_{false}, faultsOver_{false}, running_{true};
    Clock::time_point lastUndo_ = Clock::now();
    std::atomic<double> frameStartedAt_{0};
};

}  // namespace

ChaosReport runChaos(const SceneDesc& desc, const ChaosOptions& o) {
    ChaosReport report;
    std::unique_ptr<Namespaces> net;
    if (o.linkCuts) {
        net = std::make_unique<Namespaces>(o.clients);
        if (!net->ok()) {
            report.error = "cannot make network namespaces here (root and iproute2 needed)";
            return report;
        }
    }
    const ChaosStates states = chaosStates(desc);
    Master master(desc, chaosSettings(o, net.get()));
    ChaosRun run(o, net.get(), master, report);
    if (!master.waitForClients(o.clients, 120'000)) {
        report.error = "the client processes did not join";
        return report;
    }
    run.run(states);
    report.counters = master.counters();
    return report;
}

}  // namespace rtwall::testing
