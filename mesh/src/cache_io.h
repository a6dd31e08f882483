// What the mesh caches (cache.cpp) and the assembly caches (assembly_cache.cpp) share: aligned
// sections, little-endian fields, the checksum that skips its own field, and read-only mappings
// of whole files. Internal to rtwall_mesh.
#pragma once

#include <xxhash.h>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <new>
#include <utility>

namespace rtwall::detail::cacheio {

constexpr size_t align64(size_t n) { return (n + 63) & ~size_t(63); }

// Little-endian encoding.
template <class T>
T byteswap(T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    std::memcpy(&v, b, sizeof(T));
    return v;
}

template <class T>
void putLE(unsigned char* at, T v) {
    if constexpr (std::endian::native == std::endian::big) v = byteswap(v);
    std::memcpy(at, &v, sizeof(T));
}

template <class T>
T getLE(const unsigned char* at) {
    T v;
    std::memcpy(&v, at, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) v = byteswap(v);
    return v;
}

// Arrays of 4-byte values: a copy on little-endian hosts, element by element elsewhere.
template <class T>
void copyArrayLE(unsigned char* dst, const T* src, size_t n) {
    if constexpr (std::endian::native == std::endian::little) std::memcpy(dst, src, n * sizeof(T));
    else
        for (size_t i = 0; i < n; ++i) putLE(dst + i * sizeof(T), src[i]);
}

// XXH3-64 of the file with the 8 bytes at `at` (where the checksum is stored) taken as zero.
inline uint64_t checksumAt(const unsigned char* data, size_t size, size_t at) {
    XXH3_state_t* state = XXH3_createState();
    if (!state) throw std::bad_alloc();
    XXH3_64bits_reset(state);
    const unsigned char zero[8] = {};
    XXH3_64bits_update(state, data, at);
    XXH3_64bits_update(state, zero, 8);
    XXH3_64bits_update(state, data + at + 8, size - at - 8);
    const uint64_t h = XXH3_64bits_digest(state);
    XXH3_freeState(state);
    return h;
}

// A read-only mapping of a whole file. The descriptor is closed once the file is mapped (the
// mapping keeps the file), so a scene of thousands of cached meshes holds no descriptors.
class Mapping {
public:
    explicit Mapping(const std::filesystem::path& file) {
        const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0) return;
        opened_ = true;
        struct stat st {};
        void* p = MAP_FAILED;
        if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0)
            p = ::mmap(nullptr, size_t(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
        ::close(fd);
        if (p == MAP_FAILED) return;
        size_ = size_t(st.st_size);
        data_ = static_cast<const unsigned char*>(p);
        // The checksum reads the file once from start to end.
        ::madvise(p, size_, MADV_SEQUENTIAL);
    }
    // After validation, the arrays are read in BVH-build and traversal order.
    void accessRandomly() const {
        if (data_) ::madvise(const_cast<unsigned char*>(data_), size_, MADV_NORMAL);
    }
    ~Mapping() {
        if (data_) ::munmap(const_cast<unsigned char*>(data_), size_);
    }
    Mapping(const Mapping&) = delete;
    Mapping& operator=(const Mapping&) = delete;
    bool ok() const { return opened_; }
    const unsigned char* data() const { return data_; }
    size_t size() const { return size_; }

private:
    bool opened_ = false;
    const unsigned char* data_ = nullptr;
    size_t size_ = 0;
};

}  // namespace rtwall::detail::cacheio
