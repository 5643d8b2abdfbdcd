#pragma once
// Deflate (RFC 1951) for io/'s writers, by ISA-L's igzip (Debian's libisal, BSD-3-Clause): about
// five times as fast as zlib's fastest level on the arrays and images ltmsim writes, within a few
// per cent of its size (io/LtmFile.h and docs/benchmarks.md give the figures). igzip's output
// depends only on the input, the level and ISA-L's version: never on the thread or the run.
//
// Its users: io/Npz.cpp streams each .npz entry through igzip as raw deflate (its own loop, as
// libzip pulls the bytes); io/Image.cpp deflates whole in the zlib format each block of scan lines
// of an EXR file (as OpenEXR's ZIP compression reads them) and the rows of a PNG file.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ltm::io {

// igzip's levels: 1 (fastest) to 3 (smallest).
inline constexpr int kIgzipMinLevel = 1, kIgzipMaxLevel = 3;

// The working memory igzip needs at `level` (1..3): the size ISA-L documents as its default.
std::size_t igzip_level_buffer_size(int level);

// `in` deflated whole in the zlib format (RFC 1950: a 2-byte header, the deflate stream, then the
// Adler-32 of `in`) at igzip level `level` (1..3), into `out` (resized to fit), if that takes
// fewer than `limit` bytes: returns true. Returns false when it would take `limit` bytes or more
// (`out` then holds nothing of use). Throws std::runtime_error if igzip fails otherwise.
bool zlib_deflate(const unsigned char* in, std::size_t n, int level, std::size_t limit, std::vector<unsigned char>& out);

// The CRC-32 of ZIP, gzip and PNG (ISO 3309, reflected, as zlib's crc32) of p[0, n), continuing
// from `crc` (0 to start): crc32(crc32(0, a), b) is the CRC of a followed by b.
std::uint32_t crc32(std::uint32_t crc, const void* p, std::size_t n);

}  // namespace ltm::io
