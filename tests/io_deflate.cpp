// io/Deflate.h: igzip's zlib streams, read back by zlib, and their independence of what the
// thread deflated before.
#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <limits>
#include <new>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "io/Deflate.h"

// igzip's streams depend on their input alone: the same bytes from a fresh thread and from one
// that deflated other inputs at every level first (io/Deflate.cpp zeroes igzip's state and working
// memory before each stream, which keep traces of the previous one).
TEST(Deflate, TheSameInputGivesTheSameBytesWhateverCameBefore) {
    std::mt19937 rng(3);
    std::vector<unsigned char> in(100000), other(250000);
    for (std::size_t i = 0; i < in.size(); ++i)
        in[i] = static_cast<unsigned char>((i / 5) % 17 + (rng() % 5 == 0 ? rng() % 64 : 0));
    for (auto& b : other) b = static_cast<unsigned char>(rng() % 9);
    for (int level = 1; level <= 3; ++level) {
        SCOPED_TRACE("level " + std::to_string(level));
        std::string fresh;
        std::thread([&] {
            const ltm::io::Deflated d = ltm::io::zlib_deflate(in.data(), in.size(), level, in.size());
            fresh.assign(reinterpret_cast<const char*>(d.data), d.size);
        }).join();
        ASSERT_FALSE(fresh.empty());
        for (int before = 1; before <= 3; ++before) ltm::io::zlib_deflate(other.data(), other.size(), before, other.size());
        const ltm::io::Deflated d = ltm::io::zlib_deflate(in.data(), in.size(), level, in.size());
        EXPECT_TRUE(std::string(reinterpret_cast<const char*>(d.data), d.size) == fresh);
        // zlib reads it back.
        std::vector<unsigned char> back(in.size());
        uLongf n = static_cast<uLongf>(back.size());
        ASSERT_EQ(uncompress(back.data(), &n, d.data, static_cast<uLong>(d.size)), Z_OK);
        EXPECT_TRUE(n == in.size() && back == in);
    }
}

// Whatever the limit, a stream given is shorter than it and inflates to the input; too small a
// limit is refused (size 0). (igzip's bytes depend on the room it is given, so the limit is part
// of what a caller fixes for deterministic files: write_exr and write_png derive it from the size.)
TEST(Deflate, AStreamGivenIsUnderTheLimitAndWhole) {
    std::vector<unsigned char> in(50000);
    for (std::size_t i = 0; i < in.size(); ++i) in[i] = static_cast<unsigned char>(i % 251 < 100 ? 0 : i % 7);
    int refused = 0;
    for (std::size_t limit : {std::size_t(1), std::size_t(40), std::size_t(200), std::size_t(2000), in.size(), 3 * in.size()}) {
        SCOPED_TRACE("limit " + std::to_string(limit));
        const ltm::io::Deflated d = ltm::io::zlib_deflate(in.data(), in.size(), 2, limit);
        if (d.size == 0) {
            ++refused;
            continue;
        }
        EXPECT_LT(d.size, limit);
        std::vector<unsigned char> back(in.size());
        uLongf n = static_cast<uLongf>(back.size());
        ASSERT_EQ(uncompress(back.data(), &n, d.data, static_cast<uLong>(d.size)), Z_OK);
        EXPECT_TRUE(n == in.size() && back == in);
    }
    EXPECT_GE(refused, 2);  // 1 and 40 bytes cannot hold 50000 bytes of this
    EXPECT_LE(refused, 4);  // 50000 bytes and more can
}

// The CRC-32 continues across pieces and is zlib's.
TEST(Deflate, Crc32IsZlibsAndContinues) {
    const std::string s = "The quick brown fox jumps over the lazy dog";
    const auto z = static_cast<std::uint32_t>(::crc32(0L, reinterpret_cast<const Bytef*>(s.data()), static_cast<uInt>(s.size())));
    EXPECT_EQ(z, 0x414FA339u);  // the published CRC-32 of this sentence
    EXPECT_EQ(ltm::io::crc32(0, s.data(), s.size()), z);
    EXPECT_EQ(ltm::io::crc32(ltm::io::crc32(0, s.data(), 10), s.data() + 10, s.size() - 10), z);
}

namespace {

// The stream of `in` fed to a ZlibStream in pieces of `piece` bytes (the last one shorter).
std::string streamed(const std::vector<unsigned char>& in, std::size_t piece, int level, std::size_t limit) {
    ltm::io::ZlibStream s(level, limit);
    for (std::size_t at = 0; at < in.size(); at += piece) {
        const std::size_t n = std::min(piece, in.size() - at);
        if (!s.add(in.data() + at, n, at + n == in.size())) break;
    }
    const ltm::io::Deflated d = s.result();
    return {reinterpret_cast<const char*>(d.data), d.size};
}

}  // namespace

// A stream fed in pieces (as write_png feeds a picture's rows, each after its filter byte)
// inflates with zlib to the pieces joined, at every level and piece size, and its bytes are the
// same from a fresh thread and after other streams and whole deflates.
TEST(Deflate, AStreamInPiecesInflatesToThePiecesJoinedAndDependsOnThemAlone) {
    std::mt19937 rng(7);
    std::vector<unsigned char> in(300001), other(120000);
    for (std::size_t i = 0; i < in.size(); ++i)
        in[i] = static_cast<unsigned char>((i / 3) % 29 + (rng() % 7 == 0 ? rng() % 200 : 0));
    for (auto& b : other) b = static_cast<unsigned char>(rng() % 13);
    for (int level = 1; level <= 3; ++level)
        for (const std::size_t piece : {std::size_t(1), std::size_t(3001), std::size_t(65536), in.size()}) {
            SCOPED_TRACE("level " + std::to_string(level) + ", pieces of " + std::to_string(piece));
            if (piece == 1 && level != 2) continue;  // byte by byte is slow; once is enough
            const std::size_t limit = in.size() + in.size() / 1024 + 1024;
            std::string fresh;
            std::thread([&] { fresh = streamed(in, piece, level, limit); }).join();
            ASSERT_FALSE(fresh.empty());
            for (int before = 1; before <= 3; ++before) {
                ltm::io::zlib_deflate(other.data(), other.size(), before, other.size());
                streamed(other, 5000, before, other.size());
            }
            EXPECT_TRUE(streamed(in, piece, level, limit) == fresh);
            std::vector<unsigned char> back(in.size());
            uLongf n = static_cast<uLongf>(back.size());
            ASSERT_EQ(uncompress(back.data(), &n, reinterpret_cast<const Bytef*>(fresh.data()), static_cast<uLong>(fresh.size())),
                      Z_OK);
            EXPECT_TRUE(n == in.size() && back == in);
        }
}

// A stream that outgrows its limit is finished with size 0, whatever piece it outgrew it in; a
// thread's second stream while its first is open, and input after the last piece, are errors.
TEST(Deflate, AStreamOverItsLimitHasSizeZeroAndMisuseIsRefused) {
    std::mt19937 rng(9);
    std::vector<unsigned char> noise(200000);
    for (auto& b : noise) b = static_cast<unsigned char>(rng());
    for (const std::size_t limit : {std::size_t(0), std::size_t(1), std::size_t(100), std::size_t(150000)})
        EXPECT_TRUE(streamed(noise, 4096, 2, limit).empty()) << limit;
    EXPECT_FALSE(streamed(noise, 4096, 2, noise.size() + noise.size() / 1024 + 1024).empty());
    {
        ltm::io::ZlibStream s(2, 1000);
        EXPECT_THROW(ltm::io::ZlibStream(2, 1000), std::logic_error);
        EXPECT_THROW(ltm::io::zlib_deflate(noise.data(), 10, 2, 1000), std::logic_error);
        const unsigned char abc[3] = {'a', 'b', 'c'};
        ASSERT_TRUE(s.add(abc, 3, true));
        EXPECT_THROW(s.add(abc, 3, true), std::logic_error);
        EXPECT_GT(s.result().size, 0u);
    }
    ltm::io::ZlibStream after(2, 1000);  // the first one closed: a new one may open
}

// A scratch buffer whose growth fails (std::bad_alloc) is left empty, not with the size it had:
// the next, smaller request gets fresh room (a null pointer there would crash the next PNG or
// EXR write on that thread). AddressSanitizer reports an impossible allocation instead
// of throwing, so the test runs in the plain build only.
TEST(Deflate, AScratchBufferWhoseGrowthFailsIsEmptyNotDangling) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "AddressSanitizer aborts on an impossible allocation instead of throwing";
#else
    ltm::io::ScratchBytes b;
    unsigned char* p = b.get(100);
    ASSERT_NE(p, nullptr);
    p[99] = 1;
    EXPECT_THROW(b.get(std::numeric_limits<std::size_t>::max() / 2), std::bad_alloc);
    p = b.get(50);
    ASSERT_NE(p, nullptr);
    p[49] = 2;  // writable
    EXPECT_EQ(p[49], 2);
#endif
}
