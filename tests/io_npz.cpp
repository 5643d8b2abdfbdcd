// Writing .npz archives (io/Npz.h): numpy reads back values, dtypes, shapes and C order; the
// bytes are deterministic; bad arrays are refused before any file is touched.
//
// The numpy checks run /usr/bin/python3 (the `python3` on PATH may be another interpreter); they
// are skipped, with the reason, when it cannot import numpy.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "io/Npy.h"
#include "io/Npz.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;
using ltm::io::NpyArray;
using ltm::io::npy_array;
using ltm::io::write_npz;
using ltm::test::message_of;
using ltm::test::slurp;

namespace {

const char* kPython = "/usr/bin/python3";

class NpzTest : public ltm::test::LenientTempDirTest {
protected:
    // Runs `script` with /usr/bin/python3; returns its stdout (stderr goes to the test log).
    std::string python(const std::string& script, int* status) {
        const fs::path file = dir / "check.py";
        ltm::test::spit(file, script);
        FILE* p = ::popen((std::string(kPython) + " '" + file.string() + "'").c_str(), "r");
        if (!p) {
            *status = -1;
            return {};
        }
        std::string out;
        char buf[4096];
        for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
        *status = ::pclose(p);
        fs::remove(file);
        return out;
    }
};

// Empty if /usr/bin/python3 has numpy, else why not.
const std::string& numpy_missing() {
    static const std::string reason = [] {
        if (::access(kPython, X_OK) != 0) return std::string(kPython) + " does not exist";
        if (std::system((std::string(kPython) + " -c 'import numpy' > /dev/null 2>&1").c_str()) != 0)
            return std::string(kPython) + " cannot import numpy";
        return std::string();
    }();
    return reason;
}
#define REQUIRE_NUMPY()                                                \
    do {                                                               \
        if (!numpy_missing().empty()) LTM_INTEROP_SKIP() << numpy_missing(); \
    } while (0)

std::vector<std::string> lines_of(const std::string& s) {
    std::vector<std::string> out;
    std::istringstream is(s);
    for (std::string line; std::getline(is, line);) out.push_back(line);
    return out;
}

// depth: float32 3 x 4, depth[r][c] = r + c / 4 - 0.5 (exact in binary, so Python prints it
// exactly); stored row-major, so a transposed (Fortran-order) reading would show up.
struct Sample {
    std::vector<float> depth;
    std::vector<std::uint16_t> mask = {0, 1, 2, 255, 256, 1000, 65534, 65535};
    std::vector<std::int64_t> ids = {0, -1, std::numeric_limits<std::int64_t>::min(),
                                     std::numeric_limits<std::int64_t>::max(), std::int64_t(1) << 40};
    std::vector<std::int32_t> cube;  // 2 x 3 x 2
    std::vector<std::uint8_t> none;  // an empty array, shape (0, 5)
    std::string tag = "csr";
    Sample() {
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) depth.push_back(static_cast<float>(r) + static_cast<float>(c) / 4.0f - 0.5f);
        for (int i = 0; i < 12; ++i) cube.push_back(i * i - 50);
    }
    std::vector<NpyArray> arrays() const {
        return {npy_array("depth", depth, {3, 4}), npy_array("mask", mask, {2, 4}), npy_array("ids", ids),
                npy_array("cube", cube, {2, 3, 2}), npy_array("none", none, {0, 5}),
                ltm::io::npy_bytes_scalar("tag", tag)};
    }
};

TEST_F(NpzTest, NumpyReadsValuesDtypesAndShapes) {
    REQUIRE_NUMPY();
    const Sample s;
    for (int level : {1, 3, 0}) {  // deflated (igzip's fastest and best), stored
        SCOPED_TRACE("level " + std::to_string(level));
        ltm::io::NpzWriteOptions o;
        o.compression_level = level;
        write_npz(path("s.npz"), s.arrays(), o);
        EXPECT_EQ(listing(), std::vector<std::string>{"s.npz"});
        int status = 0;
        const std::string out = python(R"(
import zipfile, numpy as np
f = ')" + path("s.npz") + R"('
with zipfile.ZipFile(f) as z:
    assert z.testzip() is None
    print('entries', *[i.filename for i in z.infolist()])
with np.load(f, allow_pickle=False) as a:
    print('keys', *a.files)
    for k in a.files:
        v = a[k]
        print(k, v.dtype.str, v.shape, v.flags['C_CONTIGUOUS'])
    d = a['depth']
    print('depth', *[d[r, c].item() for r in range(3) for c in range(4)])
    print('mask', a['mask'].tolist())
    print('ids', *a['ids'].tolist())
    print('cube', a['cube'][1, 2, 1].item(), a['cube'][0, 1, 0].item())
    print('tag', a['tag'].item())
)",
                                       &status);
        ASSERT_EQ(status, 0) << out;
        const std::vector<std::string> expected = {
            "entries depth.npy mask.npy ids.npy cube.npy none.npy tag.npy",
            "keys depth mask ids cube none tag",
            "depth <f4 (3, 4) True",
            "mask <u2 (2, 4) True",
            "ids <i8 (5,) True",
            "cube <i4 (2, 3, 2) True",
            "none |u1 (0, 5) True",
            "tag |S3 () True",
            "depth -0.5 -0.25 0.0 0.25 0.5 0.75 1.0 1.25 1.5 1.75 2.0 2.25",
            "mask [[0, 1, 2, 255], [256, 1000, 65534, 65535]]",
            "ids 0 -1 -9223372036854775808 9223372036854775807 1099511627776",
            "cube 71 -46",  // element (1, 2, 1) is 11: 121 - 50; (0, 1, 0) is 2: 4 - 50
            "tag b'csr'",
        };
        EXPECT_EQ(lines_of(out), expected);
    }
}

TEST_F(NpzTest, BytesAreDeterministicAndPreamblesAligned) {
    const Sample s;
    write_npz(path("a.npz"), s.arrays());
    write_npz(path("b.npz"), s.arrays());
    const std::string a = slurp(path("a.npz"));
    EXPECT_EQ(a, slurp(path("b.npz")));
    EXPECT_EQ(a.substr(0, 4), "PK\x03\x04");
    // Level 0 stores the .npy bytes verbatim: the header of the 2-D array is readable in the file,
    // padded to 64 bytes.
    ltm::io::NpzWriteOptions stored;
    stored.compression_level = 0;
    write_npz(path("c.npz"), {npy_array("depth", s.depth, {3, 4})}, stored);
    const std::string c = slurp(path("c.npz"));
    const std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4), }";
    const std::size_t at = c.find(header);
    ASSERT_NE(at, std::string::npos);
    EXPECT_EQ(c.substr(at - 10, 8), std::string("\x93NUMPY\x01\x00", 8));
    const std::size_t len = static_cast<unsigned char>(c[at - 2]) | (static_cast<unsigned char>(c[at - 1]) << 8);
    EXPECT_EQ((10 + len) % 64, 0u);
    EXPECT_EQ(c[at - 10 + 10 + len - 1], '\n');
}

TEST_F(NpzTest, BadArraysAreRefusedBeforeAnyFileIsTouched) {
    ltm::test::spit(dir / "keep.npz", "old");
    const std::string p = path("keep.npz");
    const std::vector<float> v = {1, 2, 3, 4, 5, 6};
    const auto refused = [&](const std::vector<NpyArray>& arrays, const std::string& why) {
        const std::string msg = message_of([&] { write_npz(p, arrays, {}, "test archive"); });
        EXPECT_EQ(msg, "cannot write test archive '" + p + "': " + why);
    };
    refused({npy_array("v", v, {4, 2})},
            "array 'v' has 24 bytes, but its shape (4, 2) of '<f4' needs 8 x 4");
    refused({npy_array("v", v), npy_array("v", v)}, "two arrays are named 'v'");
    refused({npy_array("", v)}, "array 0 has an empty name");
    NpyArray odd = npy_array("odd", v);
    odd.descr = "<c8";
    refused({odd}, "array 'odd': unsupported dtype '<c8'; supported are '|b1', '<i1'..'<i8', '<u1'..'<u8', "
                   "'<f2', '<f4', '<f8' (or '>' for big-endian; '|' for one byte) and '|S<n>'");
    odd.descr = "|f4";
    refused({odd}, "array 'odd': dtype '|f4' has the wrong byte-order character: '<' or '>' for multi-byte numbers");
    ltm::io::NpzWriteOptions level;
    level.compression_level = 4;
    EXPECT_EQ(message_of([&] { write_npz(p, {npy_array("v", v)}, level); }),
              "cannot write npz archive '" + p + "': compression level 4 is outside 0..3");
    EXPECT_EQ(slurp(p), "old");
    EXPECT_EQ(listing(), std::vector<std::string>{"keep.npz"});

    const std::string nowhere = path("missing/x.npz");
    EXPECT_EQ(message_of([&] { write_npz(nowhere, {npy_array("v", v)}); }),
              "cannot write npz archive '" + nowhere + "': the folder '" + path("missing") + "' does not exist");
}

// The ZIP headers carry nothing that varies: a fixed timestamp, no extra fields, no comments;
// deflate at levels 1..3, stored at level 0. No arrays give the empty archive.
TEST_F(NpzTest, HeadersAreFixedAndLevelZeroStores) {
    REQUIRE_NUMPY();
    const Sample s;
    ltm::io::NpzWriteOptions stored;
    stored.compression_level = 0;
    write_npz(path("d.npz"), s.arrays());
    write_npz(path("s.npz"), s.arrays(), stored);
    write_npz(path("e.npz"), {});
    EXPECT_EQ(slurp(path("e.npz")), std::string("PK\x05\x06", 4) + std::string(18, '\0'));
    int status = 0;
    const std::string out = python(R"(
import struct, zipfile, numpy as np
for n in ('d', 's'):
    f = ')" + dir.string() + R"(/' + n + '.npz'
    raw = open(f, 'rb').read()
    with zipfile.ZipFile(f) as z:
        assert z.testzip() is None and z.comment == b''
        for i in z.infolist():
            local_extra = struct.unpack('<H', raw[i.header_offset + 28:i.header_offset + 30])[0]
            print(n, i.filename, i.compress_type, i.date_time, len(i.extra), local_extra, len(i.comment))
print('empty', len(np.load(')" + path("e.npz") + R"(').files))
)",
                                   &status);
    ASSERT_EQ(status, 0) << out;
    std::string expected;
    for (const char* n : {"d", "s"})
        for (const char* e : {"depth", "mask", "ids", "cube", "none", "tag"})
            expected += std::string(n) + " " + e + ".npy " + (n[0] == 'd' ? "8" : "0") + " (1980, 1, 1, 0, 0, 0) 0 0 0\n";
    EXPECT_EQ(out, expected + "empty 0\n");
}

// ZIP64 end records (libzip writes them when an archive reaches 65535 entries; numpy reads them).
// libzip cannot be made to write ZIP64 fields for a small archive, so this is the cheap way to
// get them; entries above 4 GiB would take minutes.
TEST_F(NpzTest, Zip64EndRecordsForManyEntries) {
    const std::vector<std::uint8_t> one = {7};
    std::vector<NpyArray> arrays;
    for (int i = 0; i < 65536; ++i) arrays.push_back(npy_array("a" + std::to_string(i), one));
    ltm::io::NpzWriteOptions stored;
    stored.compression_level = 0;
    write_npz(path("many.npz"), arrays, stored);
    const std::string bytes = slurp(path("many.npz"));
    EXPECT_NE(bytes.find("PK\x06\x06"), std::string::npos);  // ZIP64 end of central directory
    EXPECT_NE(bytes.find("PK\x06\x07"), std::string::npos);  // and its locator
    REQUIRE_NUMPY();
    int status = 0;
    const std::string out = python(R"(
import numpy as np
a = np.load(')" + path("many.npz") + R"(')
print(len(a.files), a['a0'].tolist(), a['a65535'].tolist())
)",
                                   &status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_EQ(out, "65536 [7] [7]\n");
}

// npy_converted: int64 values stored as int32 (as ltm.npz stores indptr), over more than one 1 MiB
// conversion block; a value that does not fit fails the write naming the array.
TEST_F(NpzTest, ConvertedArraysHoldTheValuesAndRefuseOverflow) {
    std::vector<std::int64_t> wide(300000);
    for (std::size_t i = 0; i < wide.size(); ++i) wide[i] = static_cast<std::int64_t>(i) * 7 - 1000000;
    const std::vector<std::int32_t> narrow(wide.begin(), wide.end());
    ltm::io::NpzWriteOptions stored;
    stored.compression_level = 0;
    write_npz(path("c.npz"), {ltm::io::npy_converted<std::int32_t>("v", wide, {1000, 300})}, stored);
    write_npz(path("d.npz"), {npy_array("v", narrow, {1000, 300})}, stored);
    const std::string c = slurp(path("c.npz")), d = slurp(path("d.npz"));
    // The same .npy bytes (the ZIP framing may differ: stored blocks follow the input's pieces).
    const std::string header = "{'descr': '<i4', 'fortran_order': False, 'shape': (1000, 300), }";
    ASSERT_NE(c.find(header), std::string::npos);
    std::string payload(reinterpret_cast<const char*>(narrow.data()), narrow.size() * 4);
    EXPECT_NE(c.find(payload.substr(0, 60000)), std::string::npos);
    EXPECT_NE(d.find(payload.substr(0, 60000)), std::string::npos);

    wide[123456] = std::int64_t(1) << 31;
    ltm::test::spit(dir / "keep.npz", "old");
    EXPECT_EQ(message_of([&] { write_npz(path("keep.npz"), {ltm::io::npy_converted<std::int32_t>("v", wide)}); }),
              "cannot write npz archive '" + path("keep.npz") + "': array 'v': value 2147483648 at index 123456 "
              "does not fit '<i4'");
    EXPECT_EQ(slurp(path("keep.npz")), "old");
    EXPECT_EQ(listing(), (std::vector<std::string>{"c.npz", "d.npz", "keep.npz"}));

    // A fill that gives fewer bytes than the shape needs.
    NpyArray short_one{"s", "<u2", {4}, nullptr, 8, [](std::uint64_t offset, void* out, std::size_t n) -> std::size_t {
                           const std::string six = "abcdef";
                           if (offset >= six.size()) return 0;
                           n = std::min<std::size_t>(n, six.size() - offset);
                           six.copy(static_cast<char*>(out), n, offset);
                           return n;
                       }};
    EXPECT_EQ(message_of([&] { write_npz(path("keep.npz"), {short_one}); }),
              "cannot write npz archive '" + path("keep.npz") + "': entry 's.npy' was given 134 bytes, but its "
              "shape and dtype need 136");
    EXPECT_EQ(slurp(path("keep.npz")), "old");
}

TEST_F(NpzTest, ConvertedArraysReadBackInNumpy) {
    REQUIRE_NUMPY();
    const std::vector<std::int64_t> wide = {-5, 0, 2147483647, -2147483648LL};
    const std::vector<double> doubles = {0.5, 1.0 / 3.0};
    write_npz(path("e.npz"), {ltm::io::npy_converted<std::int32_t>("i", wide),
                              ltm::io::npy_converted<float>("f", doubles, {1, 2})});
    int status = 0;
    const std::string out = python(R"(
import numpy as np
a = np.load(')" + path("e.npz") + R"(')
print(a['i'].dtype.str, a['i'].tolist())
print(a['f'].dtype.str, a['f'].shape, a['f'][0, 1] == np.float32(1.0 / 3.0))
)",
                                   &status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_EQ(out, "<i4 [-5, 0, 2147483647, -2147483648]\n<f4 (1, 2) True\n");
}

// A big-endian descr: the writer swaps the host's (little-endian) values, numpy reads the same
// numbers.
TEST_F(NpzTest, BigEndianDescrsHoldTheSameValues) {
    REQUIRE_NUMPY();
    const std::vector<std::int32_t> v = {1, -2, 70000};
    NpyArray big = npy_array("big", v);
    big.descr = ">i4";
    write_npz(path("e.npz"), {big});
    int status = 0;
    const std::string out = python(R"(
import numpy as np
a = np.load(')" + path("e.npz") + R"(')['big']
print(a.dtype.str, a.tolist())
)",
                                   &status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_EQ(out, ">i4 [1, -2, 70000]\n");
}

// The entries of a small archive as its local headers give them (libzip writes the final sizes
// and CRC-32 there, seeking back after the data; no ZIP64 fields in a small archive).
struct LocalEntry {
    std::string name, data;
    int method = -1;
    std::uint32_t crc = 0, size = 0;
};
std::vector<LocalEntry> local_entries(const std::string& zip) {
    const auto u16 = [&](std::size_t at) {
        return static_cast<std::uint32_t>(static_cast<unsigned char>(zip.at(at))) |
               static_cast<std::uint32_t>(static_cast<unsigned char>(zip.at(at + 1))) << 8;
    };
    const auto u32 = [&](std::size_t at) { return u16(at) | u16(at + 2) << 16; };
    std::vector<LocalEntry> out;
    for (std::size_t at = 0; zip.compare(at, 4, "PK\x03\x04") == 0;) {
        LocalEntry e;
        e.method = static_cast<int>(u16(at + 8));
        e.crc = u32(at + 14);
        const std::uint32_t packed = u32(at + 18);
        e.size = u32(at + 22);
        const std::size_t name = u16(at + 26), extra = u16(at + 28);
        e.name = zip.substr(at + 30, name);
        e.data = zip.substr(at + 30 + name + extra, packed);
        at += 30 + name + extra + packed;
        out.push_back(e);
    }
    return out;
}

// zlib's inflate of a raw deflate stream (independent of the deflater that wrote it); the
// stream must end exactly at the end of `packed`.
std::string inflate_raw(const std::string& packed, std::size_t size) {
    std::string out(size, '\0');
    z_stream z{};
    if (inflateInit2(&z, -15) != Z_OK) return "inflateInit2 failed";
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(packed.data()));
    z.avail_in = static_cast<uInt>(packed.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = static_cast<uInt>(out.size());
    const int r = inflate(&z, Z_FINISH);
    const bool whole = r == Z_STREAM_END && z.avail_in == 0 && z.avail_out == 0;
    inflateEnd(&z);
    return whole ? out : "inflate: code " + std::to_string(r);
}

// Deflated entries (igzip, io/Npz.cpp) hold exactly the bytes the stored archive holds, whatever
// path the input takes (the array's memory as it is; a fill; a byte swap), over many of the
// deflater's 256 KiB input pieces and its output buffer's refills; each CRC-32 in the headers is
// zlib's crc32 of those bytes (ZIP's CRC, APPNOTE 4.4.7). Read with zlib, not with the deflater's
// library. Incompressible bytes grow by less than 0.1 % (+ 1 KiB), far below the 7 % margin on
// which the choice of ZIP64 local headers rests (io/Npz.cpp, kZip64Entry).
TEST_F(NpzTest, DeflatedEntriesInflateToTheStoredBytesWithTheirCrc) {
    std::mt19937 rng(7);
    std::vector<std::uint8_t> noise(1500000);
    for (auto& b : noise) b = static_cast<std::uint8_t>(rng() >> 24);
    std::vector<float> ramp(700000);
    for (std::size_t i = 0; i < ramp.size(); ++i) ramp[i] = static_cast<float>(i % 977) * 0.25f;
    std::vector<std::int64_t> wide(600000);
    for (std::size_t i = 0; i < wide.size(); ++i) wide[i] = static_cast<std::int64_t>(i / 3) - 5000;
    std::vector<float> swapped(300000);
    for (std::size_t i = 0; i < swapped.size(); ++i) swapped[i] = static_cast<float>(i % 101);
    NpyArray big = npy_array("big", swapped);
    big.descr = ">f4";
    const std::string three = "abc";
    const std::vector<NpyArray> arrays = {npy_array("noise", noise), npy_array("ramp", ramp, {700, 1000}),
                                          ltm::io::npy_converted<std::int32_t>("narrow", wide), big,
                                          ltm::io::npy_bytes_scalar("tiny", three)};
    ltm::io::NpzWriteOptions stored;
    stored.compression_level = 0;
    write_npz(path("stored.npz"), arrays, stored);
    const std::vector<LocalEntry> plain = local_entries(slurp(path("stored.npz")));
    ASSERT_EQ(plain.size(), arrays.size());
    for (const LocalEntry& e : plain) {
        EXPECT_EQ(e.method, 0) << e.name;
        EXPECT_EQ(e.size, e.data.size()) << e.name;
        EXPECT_EQ(e.crc, crc32(0, reinterpret_cast<const Bytef*>(e.data.data()), static_cast<uInt>(e.data.size())))
            << e.name;
    }
    for (int level : {1, 2, 3}) {
        SCOPED_TRACE("level " + std::to_string(level));
        ltm::io::NpzWriteOptions o;
        o.compression_level = level;
        write_npz(path("deflated.npz"), arrays, o);
        const std::vector<LocalEntry> packed = local_entries(slurp(path("deflated.npz")));
        ASSERT_EQ(packed.size(), plain.size());
        for (std::size_t k = 0; k < packed.size(); ++k) {
            const LocalEntry &p = packed[k], &s = plain[k];
            SCOPED_TRACE(p.name);
            EXPECT_EQ(p.name, s.name);
            EXPECT_EQ(p.method, 8);
            EXPECT_EQ(p.size, s.size);
            EXPECT_EQ(p.crc, s.crc);
            EXPECT_TRUE(inflate_raw(p.data, s.size) == s.data);
            EXPECT_LE(p.data.size(), s.size + s.size / 1000 + 1024);
        }
    }
}

// A deflated entry of 4e9 bytes or more (io/Npz.cpp, kZip64Entry) gets a ZIP64 extra field in its
// local header, since libzip learns its size only after the data: the write must succeed and the
// headers hold the true sizes and CRC-32 (4e9 zero bytes from a fill; their CRC-32 is computed
// here with zlib, piece by piece). Python's zipfile reads the entry's sizes back.
TEST_F(NpzTest, AnEntryOfFourBillionBytesGetsZip64Sizes) {
    const std::uint64_t n = 4000000000ULL;
    NpyArray zeros{"zeros", "|u1", {n}, nullptr, static_cast<std::size_t>(n),
                   [n](std::uint64_t offset, void* out, std::size_t len) -> std::size_t {
                       if (offset >= n) return 0;
                       len = static_cast<std::size_t>(std::min<std::uint64_t>(len, n - offset));
                       std::memset(out, 0, len);
                       return len;
                   }};
    write_npz(path("big.npz"), {zeros});
    const std::string zip = slurp(path("big.npz"));
    const auto u16 = [&](std::size_t at) {
        return static_cast<std::uint32_t>(static_cast<unsigned char>(zip.at(at))) |
               static_cast<std::uint32_t>(static_cast<unsigned char>(zip.at(at + 1))) << 8;
    };
    const auto u32 = [&](std::size_t at) { return u16(at) | u16(at + 2) << 16; };
    const auto u64 = [&](std::size_t at) { return static_cast<std::uint64_t>(u32(at)) | static_cast<std::uint64_t>(u32(at + 4)) << 32; };
    ASSERT_EQ(zip.compare(0, 4, "PK\x03\x04"), 0);
    EXPECT_EQ(u16(8), 8u);  // deflated
    const std::size_t name = u16(26), extra = u16(28);
    ASSERT_GE(extra, 20u);
    const std::size_t x = 30 + name;
    ASSERT_EQ(u16(x), 1u);  // the ZIP64 extended information's header ID
    const std::string preamble = ltm::io::npy_preamble("|u1", {n});
    const std::uint64_t size = preamble.size() + n;
    EXPECT_EQ(u64(x + 4), size);
    const std::uint64_t packed = u64(x + 12);
    EXPECT_LT(packed, 64u << 20);  // zeros deflate to about a thousandth
    // The 32-bit fields: 0xFFFFFFFF, or (libzip 1.7, where the values fit) the values themselves.
    EXPECT_TRUE(u32(18) == 0xFFFFFFFFu || u32(18) == packed) << u32(18);
    EXPECT_TRUE(u32(22) == 0xFFFFFFFFu || u32(22) == size) << u32(22);
    uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(preamble.data()), static_cast<uInt>(preamble.size()));
    const std::vector<unsigned char> piece(1 << 20, 0);
    for (std::uint64_t done = 0; done < n; done += piece.size())
        crc = crc32(crc, piece.data(), static_cast<uInt>(std::min<std::uint64_t>(piece.size(), n - done)));
    EXPECT_EQ(u32(14), static_cast<std::uint32_t>(crc));
    EXPECT_EQ(zip.compare(x + extra + packed, 4, "PK\x01\x02"), 0);  // the central directory follows the data
    if (numpy_missing().empty()) {
        int status = 0;
        const std::string out = python("import zipfile\nfor i in zipfile.ZipFile('" + path("big.npz") +
                                           "').infolist(): print(i.filename, i.file_size, i.compress_size, i.CRC)\n",
                                       &status);
        ASSERT_EQ(status, 0) << out;
        EXPECT_EQ(out, "zeros.npy " + std::to_string(size) + " " + std::to_string(packed) + " " + std::to_string(crc) + "\n");
    }
}

}  // namespace
