// The console's backend on a WallSession: a snapshot published after every step (the display
// pipeline's tap: WallSession::addStepObserver), the thumbnail made from the shown frame there
// (downsampled on the session's thread, at most thumbnailsPerSecond and only while someone
// watches; JPEG-encoded on the asking thread), and changes posted to the session's command
// queue. The session's thread never waits on a browser: it swaps a pointer under a mutex.
#include <rtwall/web.h>

#include <rtwall/image_box.h>

#include <turbojpeg.h>

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

namespace rtwall {

namespace {

// The eyes side by side, each box-filtered to `width` pixels across (every source pixel counts
// once: rtwall/image_box.h, which display nodes sum their screens by too).
Image sideBySide(const Image& left, const Image* right) {
    if (!right || right->rgb.empty()) return left;
    Image out;
    out.width = left.width * 2;
    out.height = left.height;
    out.rgb.resize(size_t(out.width) * out.height * 3);
    const size_t row = size_t(left.width) * 3;
    for (int y = 0; y < left.height; ++y) {
        std::copy_n(left.pixel(0, y), row, out.pixel(0, y));
        std::copy_n(right->pixel(0, y), row, out.pixel(left.width, y));
    }
    return out;
}

Image thumbnailOf(const WallFrame& f, int width) {
    if (f.left.width <= 0 || f.left.height <= 0) return {};
    const Image right = f.right.rgb.empty() ? Image{} : boxPicture(f.right, width);
    return sideBySide(boxPicture(f.left, width), &right);
}

std::vector<uint8_t> jpegOf(const Image& im) {
    tjhandle tj = tjInitCompress();
    if (!tj) return {};
    unsigned char* data = nullptr;
    unsigned long size = 0;
    std::vector<uint8_t> out;
    if (tjCompress2(tj, im.rgb.data(), im.width, im.width * 3, im.height, TJPF_RGB, &data, &size, TJSAMP_420, 80, 0) == 0)
        out.assign(data, data + size);
    tjFree(data);
    tjDestroy(tj);
    return out;
}

class SessionBackend final : public ConsoleBackend {
public:
    SessionBackend(WallSession& session, const WebSettings& settings)
        : session_(session), settings_(settings), scene_(session.scene()), parts_(consoleParts(session.scene())),
          onNodes_(session.summary().onNodes) {
        latest_ = std::make_shared<ConsoleSnapshot>(take(session, nullptr));
        wanted_ = true;  // thumbnails from the start, for the first 5 s
        lastAsked_ = std::chrono::steady_clock::now();
        session.addStepObserver([this](const WallSession& s) { observe(s); });
    }

    std::shared_ptr<const ConsoleSnapshot> snapshot() override {
        std::lock_guard<std::mutex> lock(mutex_);
        return latest_;
    }
    const std::vector<ConsolePart>& parts() override { return parts_; }
    const SceneDesc* scene() override { return &scene_; }

    bool run(std::function<void(WallSession&)> command, std::chrono::milliseconds timeout) override {
        // Returns once the step that ran it has published its snapshot: a read after a change
        // sees the change.
        uint64_t ticket;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            ticket = ++posted_;
        }
        session_.post([this, command = std::move(command), ticket](WallSession& s) {
            changed_ = true;  // the next snapshot compares everything again
            ran_ = std::max(ran_, ticket);  // first: a command that throws is answered at once too
            command(s);
        });
        std::unique_lock<std::mutex> lock(mutex_);
        return cv_.wait_for(lock, timeout, [&] { return published_ >= ticket; });
    }

    std::shared_ptr<const std::vector<uint8_t>> thumbnail(uint32_t* frame) override {
        if (onNodes_) return nodesThumbnail(frame);
        std::shared_ptr<const Image> raw;
        uint32_t rawFrame = 0;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            lastAsked_ = std::chrono::steady_clock::now();
            wanted_ = true;
            if (jpegFrame_ == thumbFrame_ && jpeg_) {
                if (frame) *frame = jpegFrame_;
                return jpeg_;
            }
            raw = thumb_;
            rawFrame = thumbFrame_;
        }
        if (!raw) return nullptr;
        auto jpeg = std::make_shared<const std::vector<uint8_t>>(jpegOf(*raw));
        std::lock_guard<std::mutex> lock(mutex_);
        jpeg_ = jpeg;
        jpegFrame_ = rawFrame;
        if (frame) *frame = rawFrame;
        return jpeg;
    }

    std::optional<Image> screenshot(int eye, std::chrono::milliseconds timeout, std::string* why) override {
        if (onNodes_) return nodesScreenshot(eye, timeout, why);
        auto out = std::make_shared<std::optional<Image>>();
        const bool ran = run(
            [out, eye](WallSession& s) {
                const WallFrame& f = s.lastFrame();
                const Image& im = eye == 1 ? f.right : f.left;
                if (im.rgb.empty()) return;
                // A frame rendered at a fraction of the wall's resolution, as the wall shows it.
                const WallConfig& w = s.wallConfig();
                *out = (im.width == w.width && im.height == w.height) ? im : resizeBilinear(im, w.width, w.height);
            },
            timeout);
        if (!ran) return std::nullopt;
        return std::move(*out);
    }

    std::shared_ptr<const ConsoleSnapshot> waitNewer(uint64_t steps, std::chrono::milliseconds timeout) override {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait_for(lock, timeout, [&] { return latest_->steps > steps; });
        return latest_;
    }

private:
    // A wall on display nodes: the nodes' picture (WallSession::nodePicture), taken on the
    // asking thread (never the session's), at most thumbnailsPerSecond; one at a time, a caller
    // meanwhile gets the last one.
    std::shared_ptr<const std::vector<uint8_t>> nodesThumbnail(uint32_t* frame) {
        std::unique_lock<std::mutex> taking(pictureMutex_, std::try_to_lock);
        const auto now = std::chrono::steady_clock::now();
        if (taking.owns_lock() && now - lastThumb_ >= std::chrono::duration<double>(1.0 / settings_.thumbnailsPerSecond)) {
            const std::optional<NodePicture> pic = session_.nodePicture(settings_.thumbnailWidth, std::chrono::seconds(2));
            if (pic && !pic->left.rgb.empty()) {
                auto jpeg = std::make_shared<const std::vector<uint8_t>>(jpegOf(sideBySide(pic->left, &pic->right)));
                std::lock_guard<std::mutex> lock(mutex_);
                jpeg_ = std::move(jpeg);
                jpegFrame_ = pic->frame;
                lastThumb_ = now;
            }
        }
        std::lock_guard<std::mutex> lock(mutex_);
        if (frame) *frame = jpegFrame_;
        return jpeg_;
    }

    // Every node's pixels of one frame, at the wall's resolution as the single-PC wall's
    // screenshot; refused where a node gave none (not there, nothing presented yet, no answer)
    // or the nodes presented different frames (asked again, up to three times, a quarter of a
    // second apart, before that).
    std::optional<Image> nodesScreenshot(int eye, std::chrono::milliseconds timeout, std::string* why) {
        std::lock_guard<std::mutex> taking(pictureMutex_);
        const auto until = std::chrono::steady_clock::now() + timeout;
        std::string reason = "no frame to take yet";
        for (int attempt = 0; attempt < 3 && std::chrono::steady_clock::now() < until; ++attempt) {
            if (attempt > 0) std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(
                                 std::chrono::milliseconds(250), until - std::chrono::steady_clock::now()));
            const auto left = std::max(std::chrono::milliseconds(0), std::chrono::duration_cast<std::chrono::milliseconds>(
                                                                         until - std::chrono::steady_clock::now()));
            std::optional<NodePicture> pic = session_.nodePicture(kNodePictureEveryPixel, left);
            if (!pic) {
                reason = "no display node is there";
                break;
            }
            if (!pic->missing.empty()) {
                reason = "display node";
                reason += pic->missing.size() > 1 ? "s " : " ";
                for (size_t i = 0; i < pic->missing.size(); ++i) reason += (i ? ", '" : "'") + pic->missing[i] + "'";
                reason += " gave no pixels (not there, nothing shown yet, or no answer)";
                continue;
            }
            if (pic->left.rgb.empty()) continue;  // nothing presented yet
            if (!pic->oneFrame) {
                reason = "the display nodes presented different frames";
                continue;
            }
            Image& im = eye == 1 ? pic->right : pic->left;
            if (im.rgb.empty()) {
                reason = "the display nodes showed no right eye";
                break;
            }
            const WallConfig& w = session_.wallConfig();
            return (im.width == w.width && im.height == w.height) ? std::move(im) : resizeBilinear(im, w.width, w.height);
        }
        if (why) *why = reason;
        return std::nullopt;
    }

    WallSession& session_;
    WebSettings settings_;
    const SceneDesc scene_;  // a copy at the start: parts, meshes, instance count and origin are fixed for the run
    const std::vector<ConsolePart> parts_;
    const bool onNodes_;  // fixed for the run
    std::mutex mutex_;
    std::mutex pictureMutex_;  // a wall on display nodes: one picture taken at a time
    std::condition_variable cv_;
    std::shared_ptr<const ConsoleSnapshot> latest_;
    std::shared_ptr<const Image> thumb_;
    uint32_t thumbFrame_ = 0;
    std::shared_ptr<const std::vector<uint8_t>> jpeg_;
    uint32_t jpegFrame_ = UINT32_MAX;
    bool wanted_ = false;
    std::chrono::steady_clock::time_point lastAsked_{}, lastThumb_{};
    std::deque<std::pair<double, uint64_t>> recent_;
    uint32_t sceneSeq_ = UINT32_MAX;
    bool changed_ = false;  // a command ran since the last full snapshot (session thread only)
    uint64_t posted_ = 0;     // commands posted (mutex_)
    uint64_t ran_ = 0;        // the newest that ran (session thread only)
    uint64_t published_ = 0;  // the newest whose step's snapshot is out (mutex_)  // the last 10 steps' seconds and tile bytes

    // `before`: the last snapshot; while the scene state is the same (its sequence number), the
    // per-instance parts of it are kept, not compared again (O(instances) per changed state only).
    ConsoleSnapshot take(const WallSession& s, const ConsoleSnapshot* before) {
        ConsoleSnapshot c;
        const FrameReport& r = s.lastReport();
        c.frame = r.frame;
        c.frameMs = s.frameSeconds() * 1e3;
        if (c.frameMs > 0) {
            recent_.emplace_back(s.frameSeconds(), r.bytes);
            if (recent_.size() > 10) recent_.pop_front();
        }
        std::vector<double> secs;
        double total = 0, bytes = 0;
        for (const auto& [sec, b] : recent_) secs.push_back(sec), total += sec, bytes += double(b);
        if (!secs.empty()) {
            std::sort(secs.begin(), secs.end());
            c.fps = 1.0 / secs[secs.size() / 2];
            c.linkMegabytesPerSecond = total > 0 ? bytes * 1e-6 / total : 0;
        }
        c.tileLatencyMs = r.meanTileLatency * 1e3;
        uint64_t tiles = 0;
        for (const ClientReport& cr : r.clients) {
            c.clients.push_back({cr.id, cr.tiles, cr.busyFraction, double(cr.bytes) * 1e-6});
            tiles += cr.tiles;
        }
        c.affinity = tiles ? double(r.affinityHits) / double(tiles) : 0;
        c.tilesStolen = r.tilesStolen;
        if (const std::optional<TrackerState> t = s.tracker()) c.tracker = describeTracker(*t);
        c.steps = s.steps();
        c.operatingPoint = s.operatingPointName();
        c.onNodes = onNodes_;
        const WallConfig& w = s.wallConfig();
        c.wallWidth = w.width;
        c.wallHeight = w.height;
        c.stereo = w.stereo.mode != StereoMode::None;
        c.flying = s.flying();
        c.origin = s.scene().origin;
        // The per-instance parts (visibility, moved instances) are scanned only when the scene
        // state changed; otherwise they are the last snapshot's, equal by construction.
        bool perInstanceChanged = false;
        if (before && !changed_ && r.sceneSeq == sceneSeq_ && s.partView() == before->session.parts) {
            c.session.camera = s.camera();
            c.session.bookmarks = s.bookmarks();
            c.session.sections = s.scene().sections;
            c.session.parts = before->session.parts;
            c.session.moved = before->session.moved;
            c.session.measurements = s.measurements();
            c.visibility = before->visibility;
        } else {
            c.session = s.sessionState();
            auto visibility = std::make_shared<std::vector<Visibility>>();
            visibility->reserve(s.scene().instances.size());
            for (const InstanceDesc& in : s.scene().instances) visibility->push_back(in.visibility);
            perInstanceChanged = !before || *visibility != *before->visibility || c.session.moved != before->session.moved;
            c.visibility = std::move(visibility);
            sceneSeq_ = r.sceneSeq;
            changed_ = false;
        }
        // The operator's state without the camera: a new version when any of it changed.
        c.stateVersion = before ? before->stateVersion : 0;
        if (before && (perInstanceChanged || !(c.session.sections == before->session.sections) ||
                       !(c.session.bookmarks == before->session.bookmarks) ||
                       !(c.session.measurements == before->session.measurements) || !(c.session.parts == before->session.parts)))
            ++c.stateVersion;
        return c;
    }

    void observe(const WallSession& s) {
        std::shared_ptr<const ConsoleSnapshot> before;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            before = latest_;
        }
        auto snap = std::make_shared<const ConsoleSnapshot>(take(s, before.get()));
        const auto now = std::chrono::steady_clock::now();
        bool makeThumb;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            // On display nodes the thumbnail is the nodes' (nodesThumbnail): the master has no pixels.
            makeThumb = !onNodes_ && wanted_ && now - lastAsked_ < std::chrono::seconds(5) &&
                        now - lastThumb_ >= std::chrono::duration<double>(1.0 / settings_.thumbnailsPerSecond);
        }
        std::shared_ptr<const Image> thumb;
        if (makeThumb && !s.lastFrame().left.rgb.empty()) thumb = std::make_shared<const Image>(thumbnailOf(s.lastFrame(), settings_.thumbnailWidth));
        std::lock_guard<std::mutex> lock(mutex_);
        latest_ = std::move(snap);
        published_ = ran_;
        if (thumb) {
            thumb_ = std::move(thumb);
            thumbFrame_ = latest_->frame;
            lastThumb_ = now;
        }
        cv_.notify_all();
    }
};

}  // namespace

std::unique_ptr<ConsoleBackend> sessionBackend(WallSession& session, const WebSettings& settings) {
    return std::make_unique<SessionBackend>(session, settings);
}

}  // namespace rtwall
