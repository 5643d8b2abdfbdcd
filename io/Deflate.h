#pragma once
// Deflate (RFC 1951) for io/'s writers, by ISA-L's igzip (Debian's libisal, BSD-3-Clause): about
// five times as fast as zlib's fastest level on the arrays and images ltmsim writes, within a few
// per cent of its size (io/LtmFile.h and docs/benchmarks.md give the figures). igzip's output
// depends only on the input, the level (and for zlib_deflate the limit) and ISA-L's version, never
// on the thread or the run; ISA-L picks its kernels by the CPU's instruction sets, so another kind
// of CPU may write other bytes for the same input (which inflate to the same input).
//
// Its users: io/Npz.cpp streams each .npz entry through igzip as raw deflate (its own loop, as
// libzip pulls the bytes); io/Image.cpp deflates whole in the zlib format each block of scan lines
// of an EXR file (as OpenEXR's ZIP compression reads them) and the rows of a PNG file.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "io/Pages.h"  // ScratchBytes

namespace ltm::io {

// igzip's levels: 1 (fastest) to 3 (smallest).
inline constexpr int kIgzipMinLevel = 1, kIgzipMaxLevel = 3;

// The working memory igzip needs at `level` (1..3): the size ISA-L documents as its default.
std::size_t igzip_level_buffer_size(int level);

// Deflated bytes in a buffer of the calling thread (see zlib_deflate).
struct Deflated {
    const unsigned char* data = nullptr;
    std::size_t size = 0;  // 0: did not fit
};

// `in` deflated whole in the zlib format (RFC 1950: a 2-byte header, the deflate stream, then the
// Adler-32 of `in`) at igzip level `level` (1..3), if that takes fewer than `limit` bytes; else
// size 0. The bytes depend on `in`, `level` and `limit` (igzip adapts to the room it is given).
// The bytes are in a buffer the calling thread keeps and reuses: valid until its next call of
// zlib_deflate. (A fresh buffer per call would cost a fifth of the default scene's write stage:
// every new page costs a fault, about 10 us on a virtual machine.) Throws std::runtime_error if
// igzip fails otherwise.
// At most kMaxDeflatePiece bytes in (std::invalid_argument beyond).
inline constexpr std::size_t kMaxDeflatePiece = 0xFFFFFFFFu - (16u << 20);
Deflated zlib_deflate(const unsigned char* in, std::size_t n, int level, std::size_t limit);

// The same zlib stream as zlib_deflate's contract gives, for an input that arrives in pieces
// (igzip's stateful deflate; its bytes may differ from zlib_deflate's of the joined input, and
// depend only on the pieces, the level and the limit): so that a caller need not first copy its
// pieces into one buffer (the rows of a PNG picture, each after its filter byte). The output is
// the calling thread's, as zlib_deflate's (the two share it): valid until the thread's next
// stream. One stream at a time per thread.
class ZlibStream {
public:
    ZlibStream(int level, std::size_t limit);
    ~ZlibStream();
    ZlibStream(const ZlibStream&) = delete;
    ZlibStream& operator=(const ZlibStream&) = delete;
    // Deflates n more bytes (at most kMaxDeflatePiece in all); `last` ends the stream. False once
    // the stream does not fit in its limit (it is then finished, with size 0).
    bool add(const unsigned char* in, std::size_t n, bool last);
    // The stream once `last` was added (size 0 if it did not fit).
    Deflated result() const;

private:
    struct State;
    State* state_;
};

// A byte buffer of the calling thread's for `slot` (0..3), at least n bytes long, kept between
// calls for the same reason: for the pictures and blocks io/Image.cpp encodes. Its bytes are
// undefined until the caller writes them: a buffer that grows is replaced, not copied, and a new
// one is not cleared, so that only the pages written are faulted in (a copy and a clearing
// faulted each page up to three times).
unsigned char* thread_buffer(int slot, std::size_t n);

// The CRC-32 of ZIP, gzip and PNG (ISO 3309, reflected, as zlib's crc32) of p[0, n), continuing
// from `crc` (0 to start): crc32(crc32(0, a), b) is the CRC of a followed by b.
std::uint32_t crc32(std::uint32_t crc, const void* p, std::size_t n);

}  // namespace ltm::io
