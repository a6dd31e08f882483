// ZeroMQ CURVE keys and the master's ZAP handler (authentication of client keys).
//
// Key files are TOML: a key pair file holds `public` and `secret` (Z85, 40 characters each)
// and is written with mode 0600; a public key file holds `public` only.
#pragma once

#include <zmq.hpp>

#include <atomic>
#include <filesystem>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace rtwall::cluster {

struct KeyPair {
    std::string publicKey;  // Z85
    std::string secretKey;  // Z85
};

KeyPair makeKeyPair();
void writeKeyFiles(const KeyPair& keys, const std::filesystem::path& stem);  // stem.key, stem.pub (directories made)
void writePublicKeyFile(const std::string& publicKeyZ85, const std::filesystem::path& file);
KeyPair readKeyPair(const std::filesystem::path& file);                       // throws InputError
std::string readPublicKey(const std::filesystem::path& file);                 // .pub or .key

// Refuses libzmq releases with known vulnerabilities (before 4.3.3) and builds without CURVE.
void checkZmqVersion();

// Answers ZAP requests on the context's inproc://zeromq.zap.01: CURVE clients whose public key
// is in the allowed set pass; everyone else is refused and logged with address and key.
class ZapHandler {
public:
    // `who` names the refusing side in its log lines ("rtwall master").
    ZapHandler(zmq::context_t& ctx, const std::vector<std::string>& allowedPublicKeysZ85, std::string who = "rtwall master",
               std::string whose = "the config's client keys");
    ~ZapHandler();
    uint64_t denied() const { return denied_.load(); }
    // Replaces the allowed keys (a display node learns them from the master).
    void setAllowed(const std::vector<std::string>& allowedPublicKeysZ85);

private:
    void run();
    zmq::socket_t socket_;
    std::mutex mutex_;
    std::set<std::string> allowed_;  // 32-byte binary keys
    std::string who_, whose_;
    std::atomic<bool> stop_{false};
    std::atomic<uint64_t> denied_{0};
    std::thread thread_;
};

}  // namespace rtwall::cluster
