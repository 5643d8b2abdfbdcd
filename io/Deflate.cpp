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

unsigned char* ScratchBytes::get(std::size_t n) {
    if (n > capacity_) {
        bytes_.reset();  // the old bytes go first: they are not needed, and not copied
        const std::size_t grown = n + n / 8;
        bytes_.reset(new unsigned char[grown]);  // not value-initialised: no page is touched here
        capacity_ = grown;
    }
    return bytes_.get();
}

unsigned char* thread_buffer(int slot, std::size_t n) {
    thread_local ScratchBytes buffers[4];
    if (slot < 0 || slot > 3) throw std::invalid_argument("thread_buffer: slot " + std::to_string(slot) + " is outside 0..3");
    return buffers[slot].get(n);
}

Deflated zlib_deflate(const unsigned char* in, std::size_t n, int level, std::size_t limit) {
    constexpr std::size_t kMax = std::numeric_limits<std::uint32_t>::max();
    // igzip counts in 32 bits, and its stored-block fallback adds up to 64 KiB to the input's size
    // in 32 bits too (ISA-L 2.30): inputs stay 16 MiB clear of 4 GiB.
    if (n > kMaxDeflatePiece)
        throw std::invalid_argument("more than " + std::to_string(kMaxDeflatePiece) + " bytes to deflate in one piece");
    if (limit == 0) return {};
    thread_local std::vector<std::uint8_t> level_buf[kIgzipMaxLevel + 1];
    thread_local ScratchBytes out;  // igzip writes it; only the pages it reaches are faulted in
    std::vector<std::uint8_t>& buf = level_buf[level >= kIgzipMinLevel && level <= kIgzipMaxLevel ? level : 0];
    // The stream must depend on `in` alone, never on the thread's history (tests/app_dataset.cpp
    // compares datasets made on one thread and on two). The working memory keeps the previous
    // stream's tables, which igzip does not promise to ignore: zeroed, it is as fresh.
    if (buf.empty()) buf.resize(igzip_level_buffer_size(level));
    else std::fill(buf.begin(), buf.end(), std::uint8_t{0});
    const std::size_t room = std::min(limit - 1, kMax);
    unsigned char* const out_bytes = out.get(room);
    // Zeroed first: isal_deflate_stateless_init leaves part of the state as it was, and stack
    // garbage there made a block's bytes depend on the calls before it (the dataset test).
    isal_zstream z{};
    isal_deflate_stateless_init(&z);
    z.level = static_cast<std::uint32_t>(level);
    z.level_buf = buf.data();
    z.level_buf_size = static_cast<std::uint32_t>(buf.size());
    z.gzip_flag = IGZIP_ZLIB;
    z.end_of_stream = 1;
    z.flush = NO_FLUSH;
    z.next_in = const_cast<std::uint8_t*>(in);  // igzip only reads it
    z.avail_in = static_cast<std::uint32_t>(n);
    z.next_out = out_bytes;
    z.avail_out = static_cast<std::uint32_t>(room);
    const int r = isal_deflate_stateless(&z);
    if (r == STATELESS_OVERFLOW) return {};
    if (r != COMP_OK) throw std::runtime_error("ISA-L's deflate failed (code " + std::to_string(r) + ")");
    return {out_bytes, z.total_out};
}

std::uint32_t crc32(std::uint32_t crc, const void* p, std::size_t n) {
    return crc32_gzip_refl(crc, static_cast<const unsigned char*>(p), n);
}

}  // namespace ltm::io
