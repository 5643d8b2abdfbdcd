#pragma once
// The geometry exports' output stream (MeshExport, VtuExport): text and bytes gathered in blocks
// of about 1 MiB and written to an io::AtomicFile as each block fills, so that memory stays small
// whatever the mesh, and the file appears whole or not at all (commit the AtomicFile after
// flush()).
#include <cstring>
#include <iterator>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include <fmt/format.h>

#include "io/AtomicFile.h"

namespace ltm {

class ExportWriter {
public:
    static constexpr size_t kBlockBytes = size_t{1} << 20;

    explicit ExportWriter(io::AtomicFile& file) : file_(file) { buf_.reserve(kBlockBytes + 4096); }

    // Formatted text (fmt syntax).
    template <class... Args>
    void print(fmt::format_string<Args...> f, Args&&... args) {
        fmt::format_to(std::back_inserter(buf_), f, std::forward<Args>(args)...);
        if (buf_.size() >= kBlockBytes) flush();
    }

    // The bytes of an arithmetic value, least significant first (little-endian, as binary PLY
    // "binary_little_endian" stores every scalar), whatever the host's byte order.
    template <class T>
    void little_endian(T v) {
        static_assert(std::is_arithmetic_v<T>, "little_endian writes numbers");
        unsigned char raw[sizeof(T)];
        std::memcpy(raw, &v, sizeof(T));
#if !(defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__)
        for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(raw[i], raw[sizeof(T) - 1 - i]);
#endif
        buf_.append(reinterpret_cast<const char*>(raw), sizeof(T));
        if (buf_.size() >= kBlockBytes) flush();
    }

    // Writes out what is gathered. Call it once more before committing the file.
    void flush() {
        file_.write(buf_);
        buf_.clear();
    }

private:
    io::AtomicFile& file_;
    std::string buf_;
};

}  // namespace ltm
