// The .npy preamble codec (io/Npy.h): numpy's exact version-1.0 header and padding; versions 1.0,
// 2.0 and 3.0 parsed in steps; every malformed header refused with its reason.
//
// The numpy comparison runs /usr/bin/python3 and is skipped, with the reason, without numpy.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <cstdlib>
#include <string>
#include <vector>

#include "io/Npy.h"
#include "tests/TestSupport.h"

using ltm::io::NpyError;
using ltm::io::npy_preamble;
using ltm::io::npy_preamble_size;
using ltm::io::parse_npy_preamble;
using ltm::test::message_of;

namespace {

// A preamble of version major.0 around `dict` (no padding added).
std::string with_prefix(int major, const std::string& dict) {
    std::string s("\x93NUMPY", 6);
    s.push_back(static_cast<char>(major));
    s.push_back('\0');
    const std::size_t n = dict.size();
    for (int i = 0; i < (major == 1 ? 2 : 4); ++i) s.push_back(static_cast<char>((n >> (8 * i)) & 0xFF));
    return s + dict;
}

// Parses `preamble` the way a stream does: asks npy_preamble_size for the next length until it
// stops growing, then parses.
ltm::io::NpyHeader parse_in_steps(const std::string& preamble) {
    std::string head;
    for (std::size_t want = npy_preamble_size(head);; want = npy_preamble_size(head)) {
        if (head.size() == want) break;
        if (want > preamble.size()) throw NpyError("the test's preamble is shorter than " + std::to_string(want));
        head = preamble.substr(0, want);
    }
    return parse_npy_preamble(head);
}

std::string reason(const std::string& preamble) {
    return message_of([&] { parse_in_steps(preamble); });
}

TEST(Npy, PreambleIsNumpysVersion1Header) {
    const std::string p = npy_preamble("<f4", {3, 4});
    const std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4), }";
    ASSERT_EQ(p.size(), 128u);  // 10 + 58 + '\n' = 69 bytes, padded to the next multiple of 64
    EXPECT_EQ(p.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
    EXPECT_EQ(static_cast<unsigned char>(p[8]) | (static_cast<unsigned char>(p[9]) << 8), 118);
    EXPECT_EQ(p.substr(10, dict.size()), dict);
    EXPECT_EQ(p.substr(10 + dict.size(), 128 - 11 - dict.size()), std::string(128 - 11 - dict.size(), ' '));
    EXPECT_EQ(p.back(), '\n');

    EXPECT_EQ(ltm::io::npy_shape_repr({}), "()");
    EXPECT_EQ(ltm::io::npy_shape_repr({7}), "(7,)");
    EXPECT_EQ(ltm::io::npy_shape_repr({2, 0, 5}), "(2, 0, 5)");
    // Every length is padded to a multiple of 64, however long the shape.
    std::vector<std::uint64_t> shape;
    for (int d = 0; d < 40; ++d) {
        const std::string q = npy_preamble("|S3", shape);
        EXPECT_EQ(q.size() % 64, 0u) << d;
        EXPECT_EQ(q.back(), '\n');
        EXPECT_NE(q.find("'shape': " + ltm::io::npy_shape_repr(shape) + ", }"), std::string::npos);
        shape.push_back(1234567u * static_cast<std::uint64_t>(d + 1));
    }
    EXPECT_NE(message_of([] { npy_preamble("<f4", std::vector<std::uint64_t>(8000, 99999999)); })
                  .find("the .npy header is too long"),
              std::string::npos);
}

TEST(Npy, PreambleIsByteForByteWhatNumpySaves) {
    const char* python = "/usr/bin/python3";
    if (::access(python, X_OK) != 0 || std::system((std::string(python) + " -c 'import numpy' 2>/dev/null").c_str()) != 0)
        LTM_INTEROP_SKIP() << python << " cannot import numpy";
    const std::string script =
        "import io, sys, numpy as np\n"
        "for dt, shape in (('<f4', (3, 4)), ('<i8', (5,)), ('|S3', ()), ('>u2', (2, 0, 7)), ('<f8', (70001,)),"
        " ('|u1', tuple(range(20)))):\n"
        "    b = io.BytesIO(); np.save(b, np.zeros(shape, np.dtype(dt)), allow_pickle=False)\n"
        "    v = b.getvalue(); n = 10 + v[8] + 256 * v[9]\n"
        "    sys.stdout.write(v[:n].hex() + '\\n')\n";
    FILE* p = ::popen((std::string(python) + " -c \"" + script + "\"").c_str(), "r");
    ASSERT_NE(p, nullptr);
    std::string out;
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
    ASSERT_EQ(::pclose(p), 0) << out;
    std::vector<std::uint64_t> twenty;
    for (std::uint64_t i = 0; i < 20; ++i) twenty.push_back(i);
    const std::vector<std::pair<std::string, std::vector<std::uint64_t>>> cases = {
        {"<f4", {3, 4}}, {"<i8", {5}}, {"|S3", {}}, {">u2", {2, 0, 7}}, {"<f8", {70001}}, {"|u1", twenty}};
    std::string ours;
    for (const auto& [descr, shape] : cases) {
        for (unsigned char c : npy_preamble(descr, shape)) {
            char h[3];
            std::snprintf(h, sizeof h, "%02x", c);
            ours += h;
        }
        ours += '\n';
    }
    EXPECT_EQ(ours, out);
}

TEST(Npy, ParsesWhatItFormats) {
    const std::string p = npy_preamble("<i4", {1000, 300});
    const ltm::io::NpyHeader h = parse_in_steps(p);
    EXPECT_EQ(h.major, 1);
    EXPECT_EQ(h.minor, 0);
    EXPECT_EQ(h.preamble_size, p.size());
    EXPECT_EQ(h.descr, "<i4");
    EXPECT_EQ(h.kind, 'i');
    EXPECT_FALSE(h.big_endian);
    EXPECT_EQ(h.itemsize, 4u);
    EXPECT_FALSE(h.fortran_order);
    EXPECT_EQ(h.shape, (std::vector<std::uint64_t>{1000, 300}));
    EXPECT_EQ(h.count, 300000u);
    const ltm::io::NpyHeader s = parse_in_steps(npy_preamble("|S3", {}));
    EXPECT_EQ(s.shape, std::vector<std::uint64_t>{});
    EXPECT_EQ(s.count, 1u);
    EXPECT_EQ(s.itemsize, 3u);
}

TEST(Npy, ParsesVersions2And3AndNumpysVariations) {
    // Version 2.0: a 32-bit length; keys in another order, double quotes, no trailing comma,
    // Python 2 longs, a Fortran-order flag, extra whitespace.
    ltm::io::NpyHeader h = parse_in_steps(
        with_prefix(2, "{ \"shape\" : ( 4L ,2 ) , 'fortran_order':True,'descr':'>f8'}  \n"));
    EXPECT_EQ(h.major, 2);
    EXPECT_EQ(h.descr, ">f8");
    EXPECT_TRUE(h.big_endian);
    EXPECT_TRUE(h.fortran_order);
    EXPECT_EQ(h.shape, (std::vector<std::uint64_t>{4, 2}));
    EXPECT_EQ(h.count, 8u);
    EXPECT_EQ(h.preamble_size, 12u + 62u);
    // Version 3.0 (UTF-8 headers): a str dtype, 4 bytes per code unit.
    h = parse_in_steps(with_prefix(3, "{'descr': '<U3', 'fortran_order': False, 'shape': (), }\n"));
    EXPECT_EQ(h.major, 3);
    EXPECT_EQ(h.kind, 'U');
    EXPECT_EQ(h.itemsize, 12u);
    // '=' is the host's order; '|' is none.
    EXPECT_EQ(parse_in_steps(with_prefix(1, "{'descr': '=i2', 'fortran_order': False, 'shape': (1,)}")).itemsize, 2u);
    EXPECT_FALSE(parse_in_steps(with_prefix(1, "{'descr': '|b1', 'fortran_order': False, 'shape': (0,)}")).big_endian);
}

TEST(Npy, PreambleSizeComesInSteps) {
    const std::string p = npy_preamble("<f4", {2});
    EXPECT_EQ(npy_preamble_size(""), 8u);
    EXPECT_EQ(npy_preamble_size(p.substr(0, 5)), 8u);
    EXPECT_EQ(npy_preamble_size(p.substr(0, 8)), 10u);
    EXPECT_EQ(npy_preamble_size(p.substr(0, 10)), 128u);
    EXPECT_EQ(npy_preamble_size(p), 128u);
    const std::string v2 = with_prefix(2, "{}");
    EXPECT_EQ(npy_preamble_size(v2.substr(0, 8)), 12u);
    EXPECT_EQ(npy_preamble_size(v2.substr(0, 12)), 14u);
}

TEST(Npy, MalformedHeadersAreRefusedWithTheirReason) {
    const std::string ok = "{'descr': '<f4', 'fortran_order': False, 'shape': (3,), }";
    const auto prefix = [](const std::string& magic_version) { return std::string(magic_version.data(), 8); };
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"\x93NUMPX\x01\x00" + std::string(60, ' '), "not a .npy array (bad magic)"},
        {"PK\x03\x04 not npy", "not a .npy array (bad magic)"},
        {prefix("\x93NUMPY\x04\x00"), "unsupported .npy version 4.0"},
        {prefix("\x93NUMPY\x01\x01"), "unsupported .npy version 1.1"},
        {prefix("\x93NUMPY\x00\x00"), "unsupported .npy version 0.0"},
        {prefix("\x93NUMPY\x01\x00") + std::string("\0\0", 2), "implausible .npy header length 0"},
        {prefix("\x93NUMPY\x02\x00") + std::string("\x00\x00\x00\x02", 4), "implausible .npy header length 33554432"},
        {with_prefix(1, "['descr', '<f4']"), "bad .npy header (expected '{')"},
        {with_prefix(1, "{'descr': '<f4', 'shape': (3,)}"), "the header lacks 'descr', 'fortran_order' or 'shape'"},
        {with_prefix(1, "{'descr': '<f4', 'fortran_order': False, 'shape': (3,), 'x': 1}"), "unexpected key 'x'"},
        {with_prefix(1, "{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (3,)}"),
         "structured dtypes are not supported"},
        {with_prefix(1, "{'descr': '<f4, 'fortran_order': False, 'shape': (3,)}"), "expected ',' or '}'"},
        {with_prefix(1, "{'descr': '<f4', 'fortran_order': false, 'shape': (3,)}"), "expected True or False"},
        {with_prefix(1, "{'descr': '<f4', 'fortran_order': False, 'shape': (-3,)}"),
         "expected a non-negative integer in the shape"},
        {with_prefix(1, "{'descr': '<f4', 'fortran_order': False, 'shape': (3 4)}"), "expected ',' or ')' in the shape"},
        {with_prefix(1, "{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999999999999,)}"),
         "shape entry too large"},
        {with_prefix(1, "{'descr': '<f4' 'fortran_order': False, 'shape': (3,)}"), "expected ',' or '}'"},
        {with_prefix(1, "{'descr': '<f4', 'fortran_order': False, 'shape': (3,)"), "expected ',' or '}'"},
        {with_prefix(1, "{'descr': '<f4', 3: False}"), "expected a string"},
        {with_prefix(1, "{'descr: '<f4'"), "expected ':'"},
        {with_prefix(1, "{'descr"), "unterminated string"},
        {with_prefix(1, "{'descr': 'f4', 'fortran_order': False, 'shape': (3,)}"), "unsupported dtype 'f4'"},
        {with_prefix(1, "{'descr': '<f0', 'fortran_order': False, 'shape': (3,)}"), "unsupported dtype '<f0'"},
        {with_prefix(1, "{'descr': '<fx', 'fortran_order': False, 'shape': (3,)}"), "unsupported dtype '<fx'"},
        {with_prefix(1, "{'descr': '!f4', 'fortran_order': False, 'shape': (3,)}"), "unsupported dtype '!f4'"},
        {with_prefix(1, "{'descr': '<f4', 'fortran_order': False, 'shape': (4294967296, 4294967296)}"),
         "implausible shape"},
        {with_prefix(1, ok).substr(0, 9), "the test's preamble is shorter than 10"},  // (the helper's own check)
    };
    for (const auto& [bytes, why] : cases) {
        SCOPED_TRACE(bytes);
        const std::string msg = reason(bytes);
        EXPECT_NE(msg.find(why), std::string::npos) << msg;
    }
    // A preamble handed over incomplete or with bytes beyond its length.
    const std::string whole = with_prefix(1, ok);
    const std::string size = std::to_string(whole.size());
    EXPECT_EQ(message_of([&] { parse_npy_preamble(whole.substr(0, whole.size() - 1)); }),
              "the .npy preamble given is " + std::to_string(whole.size() - 1) + " bytes, its header says " + size);
    EXPECT_EQ(message_of([&] { parse_npy_preamble(whole + "x"); }),
              "the .npy preamble given is " + std::to_string(whole.size() + 1) + " bytes, its header says " + size);
    EXPECT_EQ(message_of([&] { parse_npy_preamble(whole); }), "(no exception)");
}

}  // namespace

// read_npy_floats (a whole .npy of floats, e.g. a user's stack of display patterns): float32 and
// float64, either byte order, C and Fortran order, all give the same values in C order; other
// dtypes, short or long data and a broken preamble are refused naming the file.
TEST(NpyFile, ReadsFloatsOfBothWidthsByteOrdersAndLayouts) {
    const std::filesystem::path dir = ltm::test::make_test_dir();
    // A (2, 3) array a[i][j] = 10 i + j - 0.5 (exact in float): C order 0..5 is
    // -0.5, 0.5, 1.5, 9.5, 10.5, 11.5; Fortran order stores a[0][0], a[1][0], a[0][1], ...
    const std::vector<double> c = {-0.5, 0.5, 1.5, 9.5, 10.5, 11.5};
    const std::vector<double> f = {-0.5, 9.5, 0.5, 10.5, 1.5, 11.5};
    auto file = [&](const std::string& name, const std::string& descr, bool fortran, const std::vector<double>& v) {
        const bool big = descr[0] == '>';
        const std::size_t size = descr[2] == '8' ? 8 : 4;
        std::string dict = "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") +
                           ", 'shape': (2, 3), }";
        std::string bytes = with_prefix(1, dict + std::string(63 - (10 + dict.size()) % 64, ' ') + "\n");
        for (double x : v) {
            unsigned char raw[8];
            if (size == 8) std::memcpy(raw, &x, 8);
            else {
                const float y = static_cast<float>(x);
                std::memcpy(raw, &y, 4);
            }
            for (std::size_t b = 0; b < size; ++b) bytes.push_back(static_cast<char>(raw[big ? size - 1 - b : b]));
        }
        ltm::test::spit(dir / name, bytes);
        return (dir / name).string();
    };
    const std::vector<float> expected(c.begin(), c.end());
    for (const auto& [descr, fortran] : std::vector<std::pair<std::string, bool>>{
             {"<f4", false}, {">f4", false}, {"<f8", false}, {">f8", false}, {"<f4", true}, {">f8", true}}) {
        const std::string p = file("a.npy", descr, fortran, fortran ? f : c);
        EXPECT_TRUE(ltm::io::is_npy_file(p));
        const ltm::io::NpyFloatArray a = ltm::io::read_npy_floats(p);
        EXPECT_EQ(a.shape, (std::vector<std::uint64_t>{2, 3})) << descr << fortran;
        EXPECT_EQ(a.values, expected) << descr << fortran;
    }
    // float64 beyond float's range rounds to infinity (the caller checks finiteness).
    EXPECT_TRUE(std::isinf(ltm::io::read_npy_floats(file("big.npy", "<f8", false, {1e300, 0, 0, 0, 0, 0})).values[0]));

    const std::string ints = file("i.npy", "<i4", false, c);
    EXPECT_NE(message_of([&] { ltm::io::read_npy_floats(ints); }).find("'" + ints + "': dtype '<i4' is not float32"),
              std::string::npos);
    std::string whole = ltm::test::slurp(file("s.npy", "<f4", false, c));
    ltm::test::spit(dir / "short.npy", whole.substr(0, whole.size() - 1));
    ltm::test::spit(dir / "long.npy", whole + "x");
    ltm::test::spit(dir / "head.npy", whole.substr(0, 20));
    for (const char* name : {"short.npy", "long.npy"})
        EXPECT_NE(message_of([&] { ltm::io::read_npy_floats((dir / name).string()); })
                      .find("needs 6 elements of 4 bytes, but it holds"),
                  std::string::npos)
            << name;
    EXPECT_NE(message_of([&] { ltm::io::read_npy_floats((dir / "head.npy").string()); }).find("truncated .npy header"),
              std::string::npos);
    EXPECT_NE(message_of([&] { ltm::io::read_npy_floats((dir / "none.npy").string()); }).find("none.npy"),
              std::string::npos);
    ltm::test::spit(dir / "image.png", "\x89PNG\r\n\x1a\n");
    EXPECT_FALSE(ltm::io::is_npy_file((dir / "image.png").string()));
    EXPECT_FALSE(ltm::io::is_npy_file((dir / "none.npy").string()));
    std::filesystem::remove_all(dir);
}
