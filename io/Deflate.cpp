#include "io/Deflate.h"

#include <isa-l/crc.h>
#include <isa-l/igzip_lib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
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

unsigned char* thread_buffer(int slot, std::size_t n) {
    thread_local ScratchBytes buffers[4];
    if (slot < 0 || slot > 3) throw std::invalid_argument("thread_buffer: slot " + std::to_string(slot) + " is outside 0..3");
    return buffers[slot].get(n);
}

namespace {

// What a thread keeps for its streams: igzip's working memory per level, the output, and the
// stream's state (82 KB, too large for the stack of a thread pool's worker).
struct ThreadDeflate {
    ScratchBytes level_buf[kIgzipMaxLevel + 1];  // in huge pages: see io/Pages.h
    ScratchBytes out;  // igzip writes it; only the pages it reaches are faulted in
    isal_zstream z;
    bool streaming = false;  // a ZlibStream holds z

    // The working memory for `level` (igzip_level_buffer_size(level) bytes), zeroed: a stream
    // must depend on its input alone, never on the thread's history (tests/app_dataset.cpp
    // compares datasets made on one thread and on two). It keeps the previous stream's tables,
    // which igzip does not promise to ignore.
    std::uint8_t* working_memory(int level) {
        const std::size_t n = igzip_level_buffer_size(level);  // checks the level
        std::uint8_t* const buf = level_buf[level].get(n);
        std::memset(buf, 0, n);
        return buf;
    }
};

ThreadDeflate& thread_deflate() {
    thread_local ThreadDeflate t;
    return t;
}

constexpr std::size_t kMaxOut = std::numeric_limits<std::uint32_t>::max();

}  // namespace

struct ZlibStream::State {
    ThreadDeflate& t;
    std::size_t room = 0, fed = 0;
    unsigned char* out = nullptr;
    bool done = false, fits = true;
};

ZlibStream::ZlibStream(int level, std::size_t limit) : state_(nullptr) {
    ThreadDeflate& t = thread_deflate();
    if (t.streaming) throw std::logic_error("ZlibStream: a thread's second stream while its first is open");
    auto s = std::make_unique<State>(State{t});
    s->room = limit == 0 ? 0 : std::min(limit - 1, kMaxOut);
    s->fits = limit != 0;
    s->done = limit == 0;  // nothing fits: finished, with size 0
    std::uint8_t* const buf = t.working_memory(level);
    s->out = t.out.get(std::max<std::size_t>(s->room, 1));
    // Zeroed first: isal_deflate_init leaves part of the state as it was (see zlib_deflate).
    t.z = isal_zstream{};
    isal_deflate_init(&t.z);
    t.z.level = static_cast<std::uint32_t>(level);
    t.z.level_buf = buf;
    t.z.level_buf_size = static_cast<std::uint32_t>(igzip_level_buffer_size(level));
    t.z.gzip_flag = IGZIP_ZLIB;
    t.z.flush = NO_FLUSH;
    t.z.next_out = s->out;
    t.z.avail_out = static_cast<std::uint32_t>(s->room);
    t.streaming = true;
    state_ = s.release();
}

ZlibStream::~ZlibStream() {
    state_->t.streaming = false;
    delete state_;
}

bool ZlibStream::add(const unsigned char* in, std::size_t n, bool last) {
    State& s = *state_;
    if (s.done && s.fits) throw std::logic_error("ZlibStream: input after the last piece");
    s.fed += n;
    if (s.fed > kMaxDeflatePiece)
        throw std::invalid_argument("more than " + std::to_string(kMaxDeflatePiece) + " bytes to deflate in one stream");
    if (!s.fits) return false;
    s.done = last;
    isal_zstream& z = s.t.z;
    z.next_in = const_cast<std::uint8_t*>(in);  // igzip only reads it
    z.avail_in = static_cast<std::uint32_t>(n);
    z.end_of_stream = last ? 1 : 0;
    // igzip takes all the input unless the output is full; at the end it runs until the stream is
    // complete. Either way a full output means the stream does not fit.
    for (;;) {
        const int r = isal_deflate(&z);
        if (r != COMP_OK) {
            s.fits = false;  // a caller that goes on gets size 0, never a truncated stream
            s.done = true;
            throw std::runtime_error("ISA-L's deflate failed (code " + std::to_string(r) + ")");
        }
        const bool finished = !last ? z.avail_in == 0 : z.internal_state.state == ZSTATE_END;
        if (finished) return true;
        if (z.avail_out == 0) {
            s.fits = false;
            s.done = true;  // finished, with size 0
            return false;
        }
    }
}

Deflated ZlibStream::result() const {
    const State& s = *state_;
    if (!s.done) throw std::logic_error("ZlibStream: the result before the last piece");
    if (!s.fits) return {};
    return {s.out, s.t.z.total_out};
}

Deflated zlib_deflate(const unsigned char* in, std::size_t n, int level, std::size_t limit) {
    constexpr std::size_t kMax = std::numeric_limits<std::uint32_t>::max();
    // igzip counts in 32 bits, and its stored-block fallback adds up to 64 KiB to the input's size
    // in 32 bits too (ISA-L 2.30): inputs stay 16 MiB clear of 4 GiB.
    if (n > kMaxDeflatePiece)
        throw std::invalid_argument("more than " + std::to_string(kMaxDeflatePiece) + " bytes to deflate in one piece");
    if (limit == 0) return {};
    ThreadDeflate& t = thread_deflate();
    if (t.streaming) throw std::logic_error("zlib_deflate: called while the thread's ZlibStream is open");
    std::uint8_t* const buf = t.working_memory(level);
    const std::size_t room = std::min(limit - 1, kMax);
    unsigned char* const out_bytes = t.out.get(room);
    // Zeroed first: isal_deflate_stateless_init leaves part of the state as it was, and stack
    // garbage there would make a block's bytes depend on the calls before it
    // (tests/io_deflate.cpp, and the dataset's bytes whatever the threads).
    isal_zstream z{};
    isal_deflate_stateless_init(&z);
    z.level = static_cast<std::uint32_t>(level);
    z.level_buf = buf;
    z.level_buf_size = static_cast<std::uint32_t>(igzip_level_buffer_size(level));
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
