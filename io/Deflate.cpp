#include "io/Deflate.h"

#include <isa-l/crc.h>
#include <isa-l/igzip_lib.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

namespace ltm::io {

std::size_t igzip_level_buffer_size(int level) {
    switch (level) {
        case 1: return ISAL_DEF_LVL1_DEFAULT;
        case 2: return ISAL_DEF_LVL2_DEFAULT;
        case 3: return ISAL_DEF_LVL3_DEFAULT;
        default: throw std::invalid_argument("igzip level " + std::to_string(level) + " is outside 1..3");
    }
}

bool zlib_deflate(const unsigned char* in, std::size_t n, int level, std::size_t limit, std::vector<unsigned char>& out) {
    constexpr std::size_t kMax = std::numeric_limits<std::uint32_t>::max();
    if (n > kMax) throw std::invalid_argument("zlib_deflate: more than 4 GiB in one piece");
    if (limit == 0) return false;
    // The working memory stays with the thread: a fresh buffer per call would be page-faulted in
    // every time (about 10 us a page on a virtual machine).
    thread_local std::vector<std::uint8_t> level_buf[kIgzipMaxLevel + 1];
    std::vector<std::uint8_t>& buf = level_buf[level >= kIgzipMinLevel && level <= kIgzipMaxLevel ? level : 0];
    if (buf.empty()) buf.resize(igzip_level_buffer_size(level));
    out.resize(std::min(limit - 1, kMax));
    isal_zstream z;
    isal_deflate_stateless_init(&z);
    z.level = static_cast<std::uint32_t>(level);
    z.level_buf = buf.data();
    z.level_buf_size = static_cast<std::uint32_t>(buf.size());
    z.gzip_flag = IGZIP_ZLIB;
    z.end_of_stream = 1;
    z.flush = NO_FLUSH;
    z.next_in = const_cast<std::uint8_t*>(in);  // igzip only reads it
    z.avail_in = static_cast<std::uint32_t>(n);
    z.next_out = out.data();
    z.avail_out = static_cast<std::uint32_t>(out.size());
    const int r = isal_deflate_stateless(&z);
    if (r == STATELESS_OVERFLOW) return false;
    if (r != COMP_OK) throw std::runtime_error("ISA-L's deflate failed (code " + std::to_string(r) + ")");
    out.resize(z.total_out);
    return true;
}

std::uint32_t crc32(std::uint32_t crc, const void* p, std::size_t n) {
    return crc32_gzip_refl(crc, static_cast<const unsigned char*>(p), n);
}

}  // namespace ltm::io
