#include "security.h"

#include <rtwall/mesh.h>
#include <rtwall/toml_reader.h>

#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <fstream>

namespace rtwall::cluster {

namespace {

std::string z85ToBinary(const std::string& z85) {
    std::string bin(32, '\0');
    if (z85.size() != 40 || !zmq_z85_decode(reinterpret_cast<uint8_t*>(bin.data()), z85.c_str())) return {};
    return bin;
}

std::string keyFrom(const std::filesystem::path& file, const char* name) {
    using namespace toml_reader;
    const toml::table root = parseFile(file);
    Reader r(file, root, "");
    std::string key = r.string(name, "", true);
    r.string(std::strcmp(name, "public") == 0 ? "secret" : "public", "");  // the other key may be there
    r.finish();
    if (z85ToBinary(key).empty())
        throw InputError(file.string() + ": key '" + name + "' is not a 40-character Z85 CURVE key");
    return key;
}

}  // namespace

KeyPair makeKeyPair() {
    char pub[41], sec[41];
    if (zmq_curve_keypair(pub, sec) != 0) throw std::runtime_error("zmq_curve_keypair failed: libzmq without CURVE");
    return {pub, sec};
}

void writeKeyFiles(const KeyPair& keys, const std::filesystem::path& stem) {
    const std::filesystem::path secretFile = stem.string() + ".key", publicFile = stem.string() + ".pub";
    // `rtwall keys keys/master` in a fresh checkout: the directory is made (only this user may
    // enter one it makes: it holds secrets).
    if (const auto dir = stem.parent_path(); !dir.empty()) {
        std::error_code ec;
        if (!std::filesystem::is_directory(dir, ec)) {
            std::filesystem::create_directories(dir, ec);
            if (ec) throw InputError(dir.string() + ": cannot make the directory for the keys (" + ec.message() + ")");
            std::filesystem::permissions(dir, std::filesystem::perms::owner_all, ec);
        }
    }
    {
        // Created with mode 0600 before anything secret is written into it.
        std::FILE* f = std::fopen(secretFile.c_str(), "w");
        if (!f) throw InputError(secretFile.string() + ": cannot write");
        chmod(secretFile.c_str(), 0600);
        std::fprintf(f, "# rtwall CURVE key pair: keep this file secret\npublic = \"%s\"\nsecret = \"%s\"\n",
                     keys.publicKey.c_str(), keys.secretKey.c_str());
        std::fclose(f);
    }
    writePublicKeyFile(keys.publicKey, publicFile);
}

void writePublicKeyFile(const std::string& publicKeyZ85, const std::filesystem::path& file) {
    std::ofstream pub(file);
    if (!pub) throw InputError(file.string() + ": cannot write");
    pub << "# rtwall CURVE public key\npublic = \"" << publicKeyZ85 << "\"\n";
    if (!pub.flush()) throw InputError(file.string() + ": cannot write");
}

KeyPair readKeyPair(const std::filesystem::path& file) { return {keyFrom(file, "public"), keyFrom(file, "secret")}; }

std::string readPublicKey(const std::filesystem::path& file) { return keyFrom(file, "public"); }

void checkZmqVersion() {
    int major, minor, patch;
    zmq_version(&major, &minor, &patch);
    if (major * 10000 + minor * 100 + patch < 40303)
        throw InputError("libzmq " + std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(patch) +
                         " is older than 4.3.3 and has known vulnerabilities; refusing to start");
    if (!zmq_has("curve")) throw InputError("this libzmq was built without CURVE; refusing to start");
}

ZapHandler::ZapHandler(zmq::context_t& ctx, const std::vector<std::string>& allowedPublicKeysZ85, std::string who,
                       std::string whose)
    : socket_(ctx, zmq::socket_type::rep), who_(std::move(who)), whose_(std::move(whose)) {
    setAllowed(allowedPublicKeysZ85);
    socket_.set(zmq::sockopt::linger, 0);
    socket_.bind("inproc://zeromq.zap.01");
    thread_ = std::thread([this] { run(); });
}

void ZapHandler::setAllowed(const std::vector<std::string>& allowedPublicKeysZ85) {
    std::set<std::string> allowed;
    for (const std::string& k : allowedPublicKeysZ85) allowed.insert(z85ToBinary(k));
    std::lock_guard lock(mutex_);
    allowed_ = std::move(allowed);
}

ZapHandler::~ZapHandler() {
    stop_ = true;
    thread_.join();
}

void ZapHandler::run() {
    zmq::pollitem_t items[] = {{socket_.handle(), 0, ZMQ_POLLIN, 0}};
    while (!stop_) {
        zmq::poll(items, 1, std::chrono::milliseconds(50));
        if (!(items[0].revents & ZMQ_POLLIN)) continue;
        // version, request id, domain, address, routing id, mechanism, credentials...
        std::vector<zmq::message_t> frames;
        do {
            zmq::message_t part;
            if (!socket_.recv(part, zmq::recv_flags::none)) break;
            const bool more = part.more();
            frames.push_back(std::move(part));
            if (!more) break;
        } while (frames.size() < 16);
        if (frames.size() < 6) continue;
        const std::string address = frames[3].to_string(), mechanism = frames[5].to_string();
        const std::string key = frames.size() > 6 ? frames[6].to_string() : std::string();
        bool ok = false;
        {
            std::lock_guard lock(mutex_);
            ok = mechanism == "CURVE" && key.size() == 32 && allowed_.count(key);
        }
        if (!ok) {
            // The first few are logged; a flood of strangers is counted (MasterCounters::refused).
            const uint64_t n = ++denied_;
            char z85[41] = "-";
            if (key.size() == 32) zmq_z85_encode(z85, reinterpret_cast<const uint8_t*>(key.data()), 32);
            if (n <= 5)
                std::fprintf(stderr, "%s: refused a client from %s (mechanism %s, key %s): not in %s%s\n", who_.c_str(),
                             address.c_str(), mechanism.c_str(), z85, whose_.c_str(),
                             n == 5 ? " (more refusals are counted, not logged)" : "");
        }
        const std::string status = ok ? "200" : "400", text = ok ? "OK" : "unknown client key";
        // Non-blocking like every other send: if libzmq's side of the ZAP exchange is gone or
        // full, the reply is dropped and that handshake fails by its own timeout.
        constexpr auto more = zmq::send_flags::sndmore | zmq::send_flags::dontwait;
        const bool replied = socket_.send(zmq::str_buffer("1.0"), more) && socket_.send(frames[1], more) &&
                             socket_.send(zmq::buffer(status), more) && socket_.send(zmq::buffer(text), more) &&
                             socket_.send(zmq::str_buffer(""), more) &&
                             socket_.send(zmq::str_buffer(""), zmq::send_flags::dontwait);
        if (!replied) std::fprintf(stderr, "%s: could not answer a ZAP request from %s\n", who_.c_str(), address.c_str());
    }
}

}  // namespace rtwall::cluster
