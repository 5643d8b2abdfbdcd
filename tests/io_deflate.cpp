// io/Deflate.h: igzip's zlib streams, read back by zlib, and their independence of what the
// thread deflated before.
#include <gtest/gtest.h>
#include <zlib.h>

#include <random>
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
