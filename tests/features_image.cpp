// Image I/O (io/Image.h): PNG and OpenEXR round trips, bit depths and colour types,
// orientation checked in the files' own bytes, 16-bit masks, bad files, pattern luminance.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfCompression.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfVersion.h>
#include <gtest/gtest.h>
#include <png.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "io/Image.h"
#include "tests/TestSupport.h"
#include "tests/Tolerances.h"

namespace fs = std::filesystem;
using ltm::Image;

namespace {

// A fresh folder `dir` per test, removed afterwards (ignoring a failure to remove it).
class ImageTest : public ltm::test::LenientTempDirTest {};

using ltm::test::message_of;
using ltm::test::slurp;
using ltm::test::spit;

bool bit_equal(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

// A PNG written directly with libpng (rows of raw bytes, 16-bit samples big-endian).
void write_raw_png(const std::string& file, int w, int h, int color_type, int bit_depth,
                   const std::vector<std::vector<png_byte>>& rows, const std::vector<png_color>& palette = {},
                   const std::vector<png_byte>& trns = {}) {
    FILE* fp = std::fopen(file.c_str(), "wb");
    ASSERT_NE(fp, nullptr);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png))) std::abort();  // a bug in this test helper
    png_init_io(png, fp);
    png_set_IHDR(png, info, static_cast<png_uint_32>(w), static_cast<png_uint_32>(h), bit_depth, color_type,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (!palette.empty()) png_set_PLTE(png, info, palette.data(), static_cast<int>(palette.size()));
    if (!trns.empty()) png_set_tRNS(png, info, trns.data(), static_cast<int>(trns.size()), nullptr);
    png_write_info(png, info);
    for (const auto& r : rows) png_write_row(png, r.data());
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    std::fclose(fp);
}

// An image whose every value is k / 255 for some integer k (exactly what 8-bit PNG holds).
Image code_value_image(int w, int h, int channels, unsigned seed) {
    Image img(w, h, channels);
    std::mt19937 rng(seed);
    for (float& v : img.data) v = static_cast<float>(rng() % 256) / 255.0f;
    img.data.front() = 0.0f;
    img.data.back() = 1.0f;
    return img;
}

// ----- a minimal independent reader of our scan-line ZIP EXR files (OpenEXR file layout,
// "Reading and Writing OpenEXR Image Files", "The OpenEXR File Layout") -----

struct ExrChannelInfo {
    std::string name;
    int type;  // 0 UINT, 1 HALF, 2 FLOAT
};
struct RawExr {
    std::vector<ExrChannelInfo> channels;
    int compression = -1;
    int xmin = 0, ymin = 0, xmax = -1, ymax = -1;
    int first_chunk_y = -1;
    std::vector<std::uint8_t> first_chunk;  // decoded bytes of the first chunk (16 scan lines for ZIP)
    std::size_t first_packed = 0;           // its size in the file
};

std::int32_t i32(const std::string& s, std::size_t p) {
    std::uint32_t v = 0;
    for (int b = 3; b >= 0; --b) v = (v << 8) | static_cast<unsigned char>(s[p + static_cast<std::size_t>(b)]);
    return static_cast<std::int32_t>(v);
}

RawExr parse_exr(const std::string& s) {
    RawExr r;
    std::size_t p = 8;  // magic, version
    for (;;) {
        const std::string name = s.c_str() + p;
        p += name.size() + 1;
        if (name.empty()) break;
        const std::string type = s.c_str() + p;
        p += type.size() + 1;
        const auto size = static_cast<std::size_t>(i32(s, p));
        p += 4;
        if (name == "channels") {
            std::size_t q = p;
            while (s[q] != '\0') {
                ExrChannelInfo c;
                c.name = s.c_str() + q;
                q += c.name.size() + 1;
                c.type = i32(s, q);
                q += 16;  // type, pLinear + reserved, xSampling, ySampling
                r.channels.push_back(c);
            }
        } else if (name == "compression") {
            r.compression = static_cast<unsigned char>(s[p]);
        } else if (name == "dataWindow") {
            r.xmin = i32(s, p);
            r.ymin = i32(s, p + 4);
            r.xmax = i32(s, p + 8);
            r.ymax = i32(s, p + 12);
        }
        p += size;
    }
    // line offset table, then the first chunk: y, packed size, data
    std::uint64_t first = 0;
    for (int b = 7; b >= 0; --b) first = (first << 8) | static_cast<unsigned char>(s[p + static_cast<std::size_t>(b)]);
    r.first_chunk_y = i32(s, first);
    const auto packed = static_cast<std::size_t>(i32(s, first + 4));
    r.first_packed = packed;
    const int width = r.xmax - r.xmin + 1, lines = std::min(16, r.ymax - r.ymin + 1);
    const std::size_t raw_size = static_cast<std::size_t>(lines) * static_cast<std::size_t>(width) * 4 * r.channels.size();
    const std::string packed_bytes = s.substr(first + 8, packed);
    if (packed == raw_size) {  // OpenEXR stores a block raw when compression does not help
        r.first_chunk.assign(packed_bytes.begin(), packed_bytes.end());
        return r;
    }
    std::vector<std::uint8_t> t(raw_size);
    uLongf n = static_cast<uLongf>(raw_size);
    if (uncompress(t.data(), &n, reinterpret_cast<const Bytef*>(packed_bytes.data()), packed) != Z_OK || n != raw_size)
        return r;
    for (std::size_t i = 1; i < t.size(); ++i) t[i] = static_cast<std::uint8_t>(t[i - 1] + t[i] - 128);  // predictor
    r.first_chunk.resize(raw_size);
    const std::size_t half = (raw_size + 1) / 2;  // interleaving: even bytes first, then odd bytes
    for (std::size_t i = 0; i < raw_size; ++i) r.first_chunk[i] = i % 2 == 0 ? t[i / 2] : t[half + i / 2];
    return r;
}

float float_at(const std::vector<std::uint8_t>& bytes, std::size_t index) {
    std::uint32_t u = 0;
    for (int b = 3; b >= 0; --b) u = (u << 8) | bytes[index * 4 + static_cast<std::size_t>(b)];
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}


// A hand-made uncompressed scan-line EXR (NO_COMPRESSION, one line per chunk) with channels of any
// pixel type, for types write_exr never writes. `channels` must be sorted by name; each value
// list holds the raw little-endian sample bytes of width x height pixels, row by row.
struct RawChannel {
    std::string name;
    int type;                        // 0 UINT (4 bytes), 1 HALF (2 bytes), 2 FLOAT (4 bytes)
    std::vector<std::uint32_t> raw;  // one sample per pixel (HALF: the 16-bit pattern)
};
std::string make_exr(int xmin, int ymin, int w, int h, const std::vector<RawChannel>& channels) {
    std::string s("\x76\x2f\x31\x01\x02\x00\x00\x00", 8);
    auto put32 = [](std::string& o, std::uint32_t v) {
        for (int i = 0; i < 4; ++i) o.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
    };
    auto attr = [&](const std::string& name, const std::string& type, const std::string& value) {
        s += name + '\0' + type + '\0';
        put32(s, static_cast<std::uint32_t>(value.size()));
        s += value;
    };
    std::string chlist;
    for (const auto& c : channels) {
        chlist += c.name + '\0';
        put32(chlist, static_cast<std::uint32_t>(c.type));
        chlist += std::string(4, '\0');  // pLinear, reserved
        put32(chlist, 1);
        put32(chlist, 1);
    }
    chlist += '\0';
    std::string box;
    for (int v : {xmin, ymin, xmin + w - 1, ymin + h - 1}) put32(box, static_cast<std::uint32_t>(v));
    std::string one, center;
    float f1 = 1.0f;
    std::uint32_t u1;
    std::memcpy(&u1, &f1, 4);
    put32(one, u1);
    put32(center, 0);
    put32(center, 0);
    attr("channels", "chlist", chlist);
    attr("compression", "compression", std::string(1, '\0'));
    attr("dataWindow", "box2i", box);
    attr("displayWindow", "box2i", box);
    attr("lineOrder", "lineOrder", std::string(1, '\0'));
    attr("pixelAspectRatio", "float", one);
    attr("screenWindowCenter", "v2f", center);
    attr("screenWindowWidth", "float", one);
    s += '\0';
    std::size_t line_bytes = 0;
    for (const auto& c : channels) line_bytes += static_cast<std::size_t>(w) * (c.type == 1 ? 2 : 4);
    const std::size_t table = s.size();
    s += std::string(8 * static_cast<std::size_t>(h), '\0');
    for (int y = 0; y < h; ++y) {
        std::uint64_t off = s.size();
        for (int i = 0; i < 8; ++i) s[table + 8 * static_cast<std::size_t>(y) + static_cast<std::size_t>(i)] = static_cast<char>((off >> (8 * i)) & 0xFF);
        put32(s, static_cast<std::uint32_t>(ymin + y));
        put32(s, static_cast<std::uint32_t>(line_bytes));
        for (const auto& c : channels)
            for (int x = 0; x < w; ++x) {
                const std::uint32_t v = c.raw[static_cast<std::size_t>(y * w + x)];
                s.push_back(static_cast<char>(v & 0xFF));
                s.push_back(static_cast<char>((v >> 8) & 0xFF));
                if (c.type != 1) {
                    s.push_back(static_cast<char>((v >> 16) & 0xFF));
                    s.push_back(static_cast<char>((v >> 24) & 0xFF));
                }
            }
    }
    return s;
}

}  // namespace

// ----- PNG -----

TEST_F(ImageTest, PngRoundTripIsExactForCodeValues) {
    for (int channels : {1, 3}) {
        SCOPED_TRACE(channels);
        const Image img = code_value_image(23, 9, channels, 5u + static_cast<unsigned>(channels));
        const std::string p = path("img.png");
        ltm::write_png(p, img);
        const Image back = ltm::read_image(p);
        EXPECT_EQ(back.width, 23);
        EXPECT_EQ(back.height, 9);
        EXPECT_EQ(back.channels, channels);
        EXPECT_TRUE(bit_equal(back.data, img.data));
        const std::string bytes = slurp(p);  // IHDR: bit depth 8, colour type 0 (gray) or 2 (RGB)
        EXPECT_EQ(static_cast<int>(bytes[24]), 8);
        EXPECT_EQ(static_cast<int>(bytes[25]), channels == 1 ? 0 : 2);
    }
    EXPECT_EQ(listing(), std::vector<std::string>{"img.png"});
}

TEST_F(ImageTest, PngWriteClampsAndRounds) {
    Image img(8, 1, 1);
    img.data = {-1.0f, 0.0f, 0.5f, 0.49f / 255.0f, 0.51f / 255.0f, 2.0f, std::numeric_limits<float>::infinity(),
                -std::numeric_limits<float>::infinity()};
    ltm::write_png(path("c.png"), img);
    const Image back = ltm::read_image(path("c.png"));
    const std::vector<float> expected = {0.0f, 0.0f, 128.0f / 255.0f, 0.0f, 1.0f / 255.0f, 1.0f, 1.0f, 0.0f};
    EXPECT_TRUE(bit_equal(back.data, expected));

    img.data[3] = std::nanf("");
    const std::string msg = message_of([&] { ltm::write_png(path("nan.png"), img); });
    EXPECT_NE(msg.find("'" + path("nan.png") + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("row 0, column 3 is NaN"), std::string::npos) << msg;
    EXPECT_FALSE(fs::exists(path("nan.png")));
}

// Previews are written from code values (ltm::Image8): the file must be the one write_png makes
// of the float Image holding those codes / 255, byte for byte, and png_code must be write_png's
// rounding: k / 255 gives k for every k; values clamp to [0, 1]; halves round up
// (0.5 -> 127.5 -> 128).
TEST_F(ImageTest, CodeValueImagesWriteTheFloatImagesFile) {
    for (int k = 0; k < 256; ++k) ASSERT_EQ(ltm::png_code(static_cast<float>(k) / 255.0f), k) << k;
    EXPECT_EQ(ltm::png_code(-1.0f), 0);
    EXPECT_EQ(ltm::png_code(2.0f), 255);
    EXPECT_EQ(ltm::png_code(0.5f), 128);
    EXPECT_EQ(ltm::png_code(0.49f / 255.0f), 0);
    EXPECT_EQ(ltm::png_code(0.51f / 255.0f), 1);
    for (int channels : {1, 3}) {
        SCOPED_TRACE(channels);
        const Image img = code_value_image(31, 7, channels, 11u + static_cast<unsigned>(channels));
        ltm::Image8 codes(img.width, img.height, img.channels);
        for (std::size_t i = 0; i < img.data.size(); ++i)
            codes.data[i] = static_cast<std::uint8_t>(std::lround(img.data[i] * 255.0f));
        ltm::write_png(path("float.png"), img);
        ltm::write_png(path("codes.png"), codes);
        EXPECT_EQ(slurp(path("codes.png")), slurp(path("float.png")));
    }
    ltm::Image8 short_data(4, 3, 3);
    short_data.data.pop_back();
    const std::string msg = message_of([&] { ltm::write_png(path("short.png"), short_data); });
    EXPECT_NE(msg.find("'" + path("short.png") + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("does not match 4 x 3 x 3"), std::string::npos) << msg;
    EXPECT_FALSE(fs::exists(path("short.png")));
}

// The PNG write_png makes, read apart without libpng (the chunk layout of ISO/IEC 15948,
// section 5, and zlib for the CRCs and the image data): the signature, IHDR first (width, height,
// depth 8, colour type 2, methods 0), IDAT chunks (random codes do not compress: a 300 x 200 RGB
// image needs several), IEND last and empty; every chunk's CRC-32 over its type and data; and the
// IDAT data, joined, one zlib stream of the rows, each after filter type 0 (None: previews are not
// filtered, see write_png). Both ways io/Image.cpp deflates the rows: whole from one buffer (up
// to kPngWholeBytes of rows with their filter bytes) and streamed a row at a time (beyond).
TEST_F(ImageTest, PngChunksAndTheirDataAreThePngSpecifications) {
    for (const auto& [w, h] : {std::pair{300, 200}, std::pair{4000, 2800}}) {
        SCOPED_TRACE(std::to_string(w) + " x " + std::to_string(h));
        const std::size_t filtered = static_cast<std::size_t>(h) * (3 * static_cast<std::size_t>(w) + 1);
        EXPECT_EQ(filtered > ltm::kPngWholeBytes, w > 300) << "the large image is streamed, the small one deflated whole";
        ltm::Image8 img(w, h, 3);
        std::mt19937 rng(7);
        for (auto& v : img.data) v = static_cast<std::uint8_t>(rng());
        ltm::write_png(path("random.png"), img);
        const std::string bytes = slurp(path("random.png"));
        ASSERT_GE(bytes.size(), 8u);
        EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
        auto be32 = [&](std::size_t at) {
            std::uint32_t v = 0;
            for (std::size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
            return v;
        };
        std::vector<std::string> types;
        std::string idat;
        std::size_t at = 8;
        while (at + 12 <= bytes.size()) {
            const std::uint32_t n = be32(at);
            ASSERT_LE(at + 12 + n, bytes.size());
            const std::string type = bytes.substr(at + 4, 4);
            const auto* typed = reinterpret_cast<const Bytef*>(bytes.data() + at + 4);
            EXPECT_EQ(be32(at + 8 + n), static_cast<std::uint32_t>(crc32(0L, typed, 4 + n))) << type << " at " << at;
            if (type == "IHDR") {
                ASSERT_EQ(n, 13u);
                EXPECT_EQ(be32(at + 8), static_cast<std::uint32_t>(w));
                EXPECT_EQ(be32(at + 12), static_cast<std::uint32_t>(h));
                EXPECT_EQ(bytes.substr(at + 16, 5), std::string("\x08\x02\x00\x00\x00", 5));
            }
            if (type == "IDAT") idat += bytes.substr(at + 8, n);
            types.push_back(type);
            at += 12 + n;
        }
        EXPECT_EQ(at, bytes.size());
        ASSERT_GE(types.size(), 5u);
        EXPECT_EQ(types.front(), "IHDR");
        EXPECT_EQ(types.back(), "IEND");
        EXPECT_EQ(std::count(types.begin(), types.end(), "IDAT"), static_cast<long>(types.size() - 2));
        std::vector<unsigned char> rows(static_cast<std::size_t>(h) * (3 * w + 1));
        uLongf got = static_cast<uLongf>(rows.size());
        ASSERT_EQ(uncompress(rows.data(), &got, reinterpret_cast<const Bytef*>(idat.data()), static_cast<uLong>(idat.size())), Z_OK);
        ASSERT_EQ(got, rows.size());
        for (int r = 0; r < h; ++r) {
            const unsigned char* row = rows.data() + static_cast<std::size_t>(r) * (3 * w + 1);
            ASSERT_EQ(row[0], 0) << "row " << r << "'s filter type";
            ASSERT_EQ(std::memcmp(row + 1, img.data.data() + static_cast<std::size_t>(r) * 3 * w, 3 * w), 0) << "row " << r;
        }
    }
}

TEST_F(ImageTest, PngBitDepthsAndColourTypes) {
    auto be16 = [](std::initializer_list<int> values) {
        std::vector<png_byte> r;
        for (int v : values) {
            r.push_back(static_cast<png_byte>(v >> 8));
            r.push_back(static_cast<png_byte>(v & 0xFF));
        }
        return r;
    };
    // 16-bit gray
    write_raw_png(path("g16.png"), 3, 2, PNG_COLOR_TYPE_GRAY, 16, {be16({0, 1, 257}), be16({32768, 65534, 65535})});
    Image g = ltm::read_image(path("g16.png"));
    ASSERT_EQ(g.channels, 1);
    ASSERT_EQ(g.width, 3);
    ASSERT_EQ(g.height, 2);
    const std::vector<int> g16 = {0, 1, 257, 32768, 65534, 65535};
    for (std::size_t i = 0; i < g16.size(); ++i) EXPECT_EQ(g.data[i], static_cast<float>(g16[i]) / 65535.0f) << i;

    // 16-bit RGB and 16-bit gray + alpha (alpha dropped)
    write_raw_png(path("rgb16.png"), 2, 1, PNG_COLOR_TYPE_RGB, 16, {be16({1000, 2000, 3000, 65535, 0, 7})});
    Image c = ltm::read_image(path("rgb16.png"));
    ASSERT_EQ(c.channels, 3);
    const std::vector<int> rgb16 = {1000, 2000, 3000, 65535, 0, 7};
    for (std::size_t i = 0; i < rgb16.size(); ++i) EXPECT_EQ(c.data[i], static_cast<float>(rgb16[i]) / 65535.0f) << i;
    write_raw_png(path("ga16.png"), 2, 1, PNG_COLOR_TYPE_GRAY_ALPHA, 16, {be16({40000, 0, 12, 65535})});
    Image ga16 = ltm::read_image(path("ga16.png"));
    ASSERT_EQ(ga16.channels, 1);
    EXPECT_EQ(ga16.data, (std::vector<float>{40000.0f / 65535.0f, 12.0f / 65535.0f}));

    // 8-bit RGBA and gray + alpha: alpha dropped
    write_raw_png(path("rgba.png"), 2, 1, PNG_COLOR_TYPE_RGBA, 8, {{10, 20, 30, 0, 255, 128, 0, 255}});
    Image ra = ltm::read_image(path("rgba.png"));
    ASSERT_EQ(ra.channels, 3);
    EXPECT_EQ(ra.data, (std::vector<float>{10 / 255.0f, 20 / 255.0f, 30 / 255.0f, 255 / 255.0f, 128 / 255.0f, 0.0f}));
    write_raw_png(path("ga.png"), 2, 1, PNG_COLOR_TYPE_GRAY_ALPHA, 8, {{77, 0, 200, 9}});
    Image ga = ltm::read_image(path("ga.png"));
    ASSERT_EQ(ga.channels, 1);
    EXPECT_EQ(ga.data, (std::vector<float>{77 / 255.0f, 200 / 255.0f}));

    // palette (with transparency, ignored) -> RGB
    write_raw_png(path("pal.png"), 3, 1, PNG_COLOR_TYPE_PALETTE, 8, {{2, 0, 1}},
                  {{255, 0, 0}, {0, 128, 0}, {1, 2, 3}}, {0, 255});
    Image pal = ltm::read_image(path("pal.png"));
    ASSERT_EQ(pal.channels, 3);
    EXPECT_EQ(pal.data, (std::vector<float>{1 / 255.0f, 2 / 255.0f, 3 / 255.0f, 1.0f, 0.0f, 0.0f, 0.0f, 128 / 255.0f,
                                            0.0f}));

    // 1-bit gray: 0 -> 0, 1 -> 1
    write_raw_png(path("g1.png"), 8, 1, PNG_COLOR_TYPE_GRAY, 1, {{0xB1}});
    Image g1 = ltm::read_image(path("g1.png"));
    ASSERT_EQ(g1.channels, 1);
    EXPECT_EQ(g1.data, (std::vector<float>{1, 0, 1, 1, 0, 0, 0, 1}));
}

TEST_F(ImageTest, PngRowZeroIsTheTopRowOfTheFile) {
    Image img(6, 4, 1);
    for (int c = 0; c < 6; ++c) img.at(0, c) = 1.0f;  // bright top row
    img.at(3, 5) = 0.2f;
    ltm::write_png(path("top.png"), img);
    // Decoded by libpng's simplified API, independently of read_image: its row 0 is the file's first.
    png_image pi{};
    pi.version = PNG_IMAGE_VERSION;
    ASSERT_TRUE(png_image_begin_read_from_file(&pi, path("top.png").c_str()));
    EXPECT_EQ(pi.format, static_cast<png_uint_32>(PNG_FORMAT_GRAY));
    std::vector<png_byte> buf(PNG_IMAGE_SIZE(pi));
    ASSERT_TRUE(png_image_finish_read(&pi, nullptr, buf.data(), 0, nullptr));
    for (int c = 0; c < 6; ++c) {
        EXPECT_EQ(buf[static_cast<std::size_t>(c)], 255) << c;
        EXPECT_EQ(buf[6 + static_cast<std::size_t>(c)], 0) << c;
    }
    EXPECT_EQ(buf[3 * 6 + 5], 51);  // round(0.2 * 255)
    const Image back = ltm::read_image(path("top.png"));
    EXPECT_EQ(back.at(0, 0), 1.0f);
    EXPECT_EQ(back.at(1, 0), 0.0f);
}

// ----- OpenEXR -----

TEST_F(ImageTest, ExrRoundTripIsBitExactAndKeepsNames) {
    const int w = 13, h = 37;
    const std::size_t n = static_cast<std::size_t>(w * h);
    std::mt19937 rng(3);
    std::vector<std::pair<std::string, std::vector<float>>> channels = {
        {"BrightField", {}}, {"ScatterCount", {}}, {"ScatterWidth", {}}, {"a.b c", {}}};
    for (auto& [name, v] : channels) {
        v.resize(n);
        for (float& x : v) x = std::ldexp(std::uniform_real_distribution<float>(-1.0f, 1.0f)(rng), int(rng() % 60) - 30);
    }
    auto& bf = channels[0].second;
    bf[0] = -0.0f;
    bf[1] = std::numeric_limits<float>::denorm_min();
    bf[2] = std::numeric_limits<float>::max();
    bf[3] = std::numeric_limits<float>::infinity();
    bf[4] = 1e-40f;
    ltm::write_exr(path("f.exr"), w, h, channels);
    EXPECT_EQ(listing(), std::vector<std::string>{"f.exr"});

    int rw = 0, rh = 0;
    const auto back = ltm::read_exr_channels(path("f.exr"), &rw, &rh);
    EXPECT_EQ(rw, w);
    EXPECT_EQ(rh, h);
    ASSERT_EQ(back.size(), channels.size());
    for (const auto& [name, values] : channels) {
        SCOPED_TRACE(name);
        const auto it = std::find_if(back.begin(), back.end(), [&](const auto& c) { return c.first == name; });
        ASSERT_NE(it, back.end());
        EXPECT_TRUE(bit_equal(it->second, values));
    }

    // In the file itself: the names, FLOAT type (2) and ZIP compression (3).
    const RawExr raw = parse_exr(slurp(path("f.exr")));
    std::vector<std::string> names;
    for (const auto& c : raw.channels) {
        names.push_back(c.name);
        EXPECT_EQ(c.type, 2) << c.name;
    }
    EXPECT_EQ(names, (std::vector<std::string>{"BrightField", "ScatterCount", "ScatterWidth", "a.b c"}));
    EXPECT_EQ(raw.compression, 3);
    EXPECT_EQ(raw.xmin, 0);
    EXPECT_EQ(raw.ymin, 0);
    EXPECT_EQ(raw.xmax, w - 1);
    EXPECT_EQ(raw.ymax, h - 1);
}

// write_exr lays the file out by hand (io/Image.cpp): OpenEXR's own reader (Imf::InputFile, the
// oracle here) must find the header Imf::Header(width, height) gives with ZIP compression, the
// long-names flag for a name over 31 characters (OpenEXR's rule), and every value bit for bit,
// in deflated blocks (smooth values) and stored ones (noise), with a last block shorter than 16
// lines. The independent parser above decodes the first block from the file's bytes with zlib.
// Channels given as views of an interleaved x, y array (stride 2, as the render's reference
// means) are written as the two halves would be: OpenEXR reads back each half bit for bit, and
// the file's bytes are those of write_exr given the halves as vectors. A view of the wrong count
// is refused with the path.
TEST_F(ImageTest, StridedChannelViewsWriteTheHalvesOfAnInterleavedArray) {
    const int w = 29, h = 21;
    const std::size_t n = static_cast<std::size_t>(w * h);
    std::vector<float> xy(2 * n);
    std::mt19937 rng(5);
    for (auto& v : xy) v = std::uniform_real_distribution<float>(-50.0f, 50.0f)(rng);
    std::vector<float> x(n), y(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = xy[2 * i], y[i] = xy[2 * i + 1];
    ltm::write_exr(path("views.exr"), w, h, std::vector<ltm::ExrChannelView>{{"MeanX", xy.data(), n, 2}, {"MeanY", xy.data() + 1, n, 2}});
    ltm::write_exr(path("vectors.exr"), w, h, {{"MeanX", x}, {"MeanY", y}});
    EXPECT_EQ(slurp(path("views.exr")), slurp(path("vectors.exr")));
    int rw = 0, rh = 0;
    const auto back = ltm::read_exr_channels(path("views.exr"), &rw, &rh);
    ASSERT_EQ(back.size(), 2u);
    EXPECT_EQ(rw, w);
    EXPECT_EQ(rh, h);
    EXPECT_EQ(back[0].first, "MeanX");
    EXPECT_TRUE(bit_equal(back[0].second, x));
    EXPECT_EQ(back[1].first, "MeanY");
    EXPECT_TRUE(bit_equal(back[1].second, y));
    try {
        ltm::write_exr(path("short.exr"), w, h, std::vector<ltm::ExrChannelView>{{"MeanX", xy.data(), n - 1, 2}});
        ADD_FAILURE() << "a view of n - 1 values was accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("short.exr"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(path("short.exr")));
}

TEST_F(ImageTest, OpenExrReadsTheHeaderAndEveryBlockWriteExrLaysOut) {
    const int w = 37, h = 45;  // blocks of 16, 16 and 13 lines
    const std::size_t n = static_cast<std::size_t>(w * h);
    const std::string long_name = "AChannelNameOfMoreThanThirtyOneCharacters";
    std::vector<std::pair<std::string, std::vector<float>>> channels = {{"Smooth", {}}, {long_name, {}}, {"Noise", {}}};
    std::mt19937 rng(11);
    for (std::size_t i = 0; i < n; ++i) {
        channels[0].second.push_back(static_cast<float>(i / 7) * 0.5f);
        channels[1].second.push_back(static_cast<float>(i % 5));
        channels[2].second.push_back(std::uniform_real_distribution<float>(-1.0f, 1.0f)(rng));
    }
    // Smooth alone (its blocks deflate), Noise alone (stored: deflate does not shrink it), all three.
    for (int kind = 0; kind < 3; ++kind) {
        SCOPED_TRACE("case " + std::to_string(kind));
        const bool with_long_name = kind == 2;
        auto given = channels;
        if (kind == 0) given = {channels[0]};
        if (kind == 1) given = {channels[2]};
        ltm::write_exr(path("b.exr"), w, h, given);
        Imf::InputFile in(path("b.exr").c_str());
        const Imf::Header& header = in.header();
        EXPECT_EQ(header.compression(), Imf::ZIP_COMPRESSION);
        EXPECT_EQ(header.lineOrder(), Imf::INCREASING_Y);
        EXPECT_EQ(header.dataWindow().min.x, 0);
        EXPECT_EQ(header.dataWindow().max.x, w - 1);
        EXPECT_EQ(header.dataWindow().max.y, h - 1);
        EXPECT_EQ(header.displayWindow(), header.dataWindow());
        EXPECT_EQ(header.pixelAspectRatio(), 1.0f);
        EXPECT_EQ(header.screenWindowWidth(), 1.0f);
        std::vector<std::string> attributes;
        for (auto it = header.begin(); it != header.end(); ++it) attributes.push_back(it.name());
        EXPECT_EQ(attributes, (std::vector<std::string>{"channels", "compression", "dataWindow", "displayWindow",
                                                        "lineOrder", "pixelAspectRatio", "screenWindowCenter",
                                                        "screenWindowWidth"}));
        EXPECT_EQ((in.version() & Imf::LONG_NAMES_FLAG) != 0, with_long_name);
        EXPECT_EQ(Imf::getVersion(in.version()), 2);
        Imf::FrameBuffer fb;
        std::vector<std::vector<float>> back(given.size(), std::vector<float>(n, -7.0f));
        for (std::size_t c = 0; c < given.size(); ++c) {
            ASSERT_NE(header.channels().findChannel(given[c].first), nullptr) << given[c].first;
            EXPECT_EQ(header.channels()[given[c].first].type, Imf::FLOAT);
            fb.insert(given[c].first, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(back[c].data()), sizeof(float),
                                                 sizeof(float) * static_cast<std::size_t>(w)));
        }
        in.setFrameBuffer(fb);
        in.readPixels(0, h - 1);
        for (std::size_t c = 0; c < given.size(); ++c) EXPECT_TRUE(bit_equal(back[c], given[c].second)) << given[c].first;
        const RawExr raw = parse_exr(slurp(path("b.exr")));
        const std::size_t block = static_cast<std::size_t>(16 * w * 4) * given.size();
        ASSERT_EQ(raw.first_chunk.size(), block);
        if (kind == 0) {
            EXPECT_LT(raw.first_packed, block / 4);
        } else if (kind == 1) {
            EXPECT_EQ(raw.first_packed, block);
        }
        // Line 0's channels by name (the long name, Noise, Smooth; those present): the last is checked.
        const std::size_t last = given.size() - 1;
        const auto& line0 = kind == 1 ? channels[2].second : channels[0].second;
        for (int x = 0; x < w; ++x)
            EXPECT_EQ(float_at(raw.first_chunk, last * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)),
                      line0[static_cast<std::size_t>(x)]);
    }
}

TEST_F(ImageTest, ExrRowZeroIsTheFirstScanLineOfTheFile) {
    const int w = 5, h = 20;
    std::vector<float> bright(static_cast<std::size_t>(w * h), 0.0f), rows(static_cast<std::size_t>(w * h));
    for (int c = 0; c < w; ++c) bright[static_cast<std::size_t>(c)] = 1.0f;  // top row bright
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) rows[static_cast<std::size_t>(r * w + c)] = static_cast<float>(r);
    ltm::write_exr(path("o.exr"), w, h, {{"ScatterCount", rows}, {"BrightField", bright}});
    const RawExr raw = parse_exr(slurp(path("o.exr")));
    ASSERT_EQ(raw.first_chunk_y, 0);
    ASSERT_EQ(raw.first_chunk.size(), static_cast<std::size_t>(16 * w * 2 * 4));
    // Scan line 0 of the file: BrightField (channels are stored sorted by name), then ScatterCount.
    for (int c = 0; c < w; ++c) {
        EXPECT_EQ(float_at(raw.first_chunk, static_cast<std::size_t>(c)), 1.0f) << c;
        EXPECT_EQ(float_at(raw.first_chunk, static_cast<std::size_t>(w + c)), 0.0f) << c;
        // scan line 1
        EXPECT_EQ(float_at(raw.first_chunk, static_cast<std::size_t>(2 * w + c)), 0.0f) << c;
        EXPECT_EQ(float_at(raw.first_chunk, static_cast<std::size_t>(3 * w + c)), 1.0f) << c;
    }
    const auto back = ltm::read_exr_channels(path("o.exr"), nullptr, nullptr);
    ASSERT_EQ(back.size(), 2u);
    EXPECT_EQ(back[0].first, "BrightField");
    EXPECT_EQ(back[0].second, bright);
    EXPECT_EQ(back[1].second, rows);
}

TEST_F(ImageTest, ExrHalfAndUintChannelsAndAnOffsetDataWindow) {
    // HALF 1, 0.5, -2, 65504, 2^-24 (the smallest subnormal), 0; UINT 7, 4e9, ...
    spit(path("hu.exr"), make_exr(10, 20, 3, 2,
                                  {{"H", 1, {0x3C00, 0x3800, 0xC000, 0x7BFF, 0x0001, 0x0000}},
                                   {"U", 0, {7, 4000000000u, 0, 1, 2, 3}}}));
    int w = 0, h = 0;
    const auto ch = ltm::read_exr_channels(path("hu.exr"), &w, &h);
    EXPECT_EQ(w, 3);
    EXPECT_EQ(h, 2);
    ASSERT_EQ(ch.size(), 2u);
    EXPECT_EQ(ch[0].first, "H");
    EXPECT_EQ(ch[0].second, (std::vector<float>{1.0f, 0.5f, -2.0f, 65504.0f, std::ldexp(1.0f, -24), 0.0f}));
    EXPECT_EQ(ch[1].first, "U");
    EXPECT_EQ(ch[1].second, (std::vector<float>{7.0f, 4e9f, 0.0f, 1.0f, 2.0f, 3.0f}));
    const std::string msg = message_of([&] { ltm::read_image(path("hu.exr")); });
    EXPECT_NE(msg.find("it has the channels H, U: a pattern needs a single channel, or channels R, G and B"),
              std::string::npos)
        << msg;

    // a single HALF channel is a pattern; row 0 is the data window's top line (y = ymin)
    spit(path("y.exr"), make_exr(-4, 7, 2, 2, {{"Y", 1, {0x3C00, 0x3C00, 0x0000, 0x3800}}}));
    const Image img = ltm::read_image(path("y.exr"));
    ASSERT_EQ(img.channels, 1);
    EXPECT_EQ(img.data, (std::vector<float>{1.0f, 1.0f, 0.0f, 0.5f}));
    const std::string whole = slurp(path("y.exr"));
    spit(path("y_cut.exr"), whole.substr(0, whole.size() - 6));
    const std::string cut = message_of([&] { ltm::read_image(path("y_cut.exr")); });
    EXPECT_NE(cut.find("cannot read image '" + path("y_cut.exr") + "'"), std::string::npos) << cut;
}

TEST_F(ImageTest, ExrAsPattern) {
    const int w = 3, h = 2;
    const std::size_t n = 6;
    // a single channel, whatever its name
    std::vector<float> y = {0.0f, 0.25f, 0.5f, 0.75f, 1.0f, 2.0f};
    ltm::write_exr(path("y.exr"), w, h, {{"Pattern", y}});
    Image one = ltm::read_image(path("y.exr"));
    EXPECT_EQ(one.channels, 1);
    EXPECT_EQ(one.width, 3);
    EXPECT_EQ(one.height, 2);
    EXPECT_EQ(one.data, y);
    // R, G, B (and A, ignored) in that order, whatever the file order
    ltm::write_exr(path("rgb.exr"), w, h,
                   {{"B", std::vector<float>(n, 0.3f)}, {"A", std::vector<float>(n, 9.0f)},
                    {"G", std::vector<float>(n, 0.2f)}, {"R", std::vector<float>(n, 0.1f)}});
    Image rgb = ltm::read_image(path("rgb.exr"));
    ASSERT_EQ(rgb.channels, 3);
    EXPECT_EQ(rgb.at(1, 2, 0), 0.1f);
    EXPECT_EQ(rgb.at(1, 2, 1), 0.2f);
    EXPECT_EQ(rgb.at(1, 2, 2), 0.3f);
    // anything else: an error listing the channels
    ltm::write_exr(path("two.exr"), w, h, {{"Z", std::vector<float>(n)}, {"A", std::vector<float>(n)}});
    const std::string msg = message_of([&] { ltm::read_image(path("two.exr")); });
    EXPECT_NE(msg.find("cannot read image '" + path("two.exr") + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("channels A, Z"), std::string::npos) << msg;
}

TEST_F(ImageTest, ContentNotExtensionDecides) {
    const Image img = code_value_image(4, 3, 1, 1);
    ltm::write_png(path("really_png.exr"), img);
    EXPECT_TRUE(bit_equal(ltm::read_image(path("really_png.exr")).data, img.data));
    ltm::write_exr(path("really_exr.png"), 4, 3, {{"Y", img.data}});
    EXPECT_TRUE(bit_equal(ltm::read_image(path("really_exr.png")).data, img.data));
    const std::string msg = message_of([&] { ltm::read_exr_channels(path("really_png.exr"), nullptr, nullptr); });
    EXPECT_NE(msg.find("cannot read EXR image '" + path("really_png.exr") + "': not an OpenEXR file"),
              std::string::npos)
        << msg;
}

// ----- bad files and failed writes -----

TEST_F(ImageTest, BadFilesThrowNamingTheFile) {
    ltm::write_png(path("good.png"), code_value_image(40, 30, 3, 2));
    const std::string png = slurp(path("good.png"));
    std::vector<float> v(64 * 64);
    std::mt19937 rng(1);
    for (float& x : v) x = std::uniform_real_distribution<float>(0, 1)(rng);
    ltm::write_exr(path("good.exr"), 64, 64, {{"Y", v}});
    const std::string exr = slurp(path("good.exr"));

    spit(path("empty.png"), "");
    spit(path("text.png"), "P2\n# not really an image\n2 2 255\n0 1 2 3\n");
    spit(path("cut.png"), png.substr(0, png.size() / 2));
    spit(path("header_only.png"), png.substr(0, 30));
    std::string crc = png;
    crc[png.size() / 2] = static_cast<char>(crc[png.size() / 2] ^ 0x10);  // inside IDAT: CRC or zlib error
    spit(path("flipped.png"), crc);
    spit(path("cut.exr"), exr.substr(0, exr.size() / 2));
    spit(path("header_cut.exr"), exr.substr(0, 40));
    fs::create_directory(path("folder.png"));
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"empty.png", "the file is empty"},
        {"text.png", "not a PNG or OpenEXR file"},
        {"cut.png", "corrupt or unsupported PNG"},
        {"header_only.png", "corrupt or unsupported PNG"},
        {"flipped.png", "corrupt or unsupported PNG"},
        {"cut.exr", "OpenEXR"},
        {"header_cut.exr", "OpenEXR"},
        {"missing.png", "no such file"},
        {"folder.png", "it is a folder"},
    };
    for (const auto& [name, what] : cases) {
        SCOPED_TRACE(name);
        const std::string msg = message_of([&] { ltm::read_image(path(name)); });
        EXPECT_NE(msg.find("cannot read image '" + path(name) + "': "), std::string::npos) << msg;
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
    const std::string msg = message_of([&] { ltm::read_exr_channels(path("cut.exr"), nullptr, nullptr); });
    EXPECT_NE(msg.find("cannot read EXR image '" + path("cut.exr") + "'"), std::string::npos) << msg;
}

TEST_F(ImageTest, FailedWritesNameThePathAndLeaveTheTarget) {
    const Image img = code_value_image(4, 4, 1, 3);
    ltm::write_png(path("keep.png"), img);
    ltm::write_exr(path("keep.exr"), 4, 4, {{"Y", img.data}});
    const std::string png = slurp(path("keep.png")), exr = slurp(path("keep.exr"));

    Image two(4, 4, 2);
    std::string msg = message_of([&] { ltm::write_png(path("keep.png"), two); });
    EXPECT_NE(msg.find("cannot write PNG image '" + path("keep.png") + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("2 channels"), std::string::npos) << msg;
    msg = message_of([&] { ltm::write_exr(path("keep.exr"), 4, 4, {{"Y", std::vector<float>(15)}}); });
    EXPECT_NE(msg.find("cannot write EXR image '" + path("keep.exr") + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("channel 'Y' has 15 values, expected 4 x 4 = 16"), std::string::npos) << msg;
    msg = message_of([&] { ltm::write_exr(path("keep.exr"), 4, 4, {{"Y", img.data}, {"Y", img.data}}); });
    EXPECT_NE(msg.find("two channels are named 'Y'"), std::string::npos) << msg;
    msg = message_of([&] { ltm::write_exr(path("keep.exr"), 4, 4, {{"", img.data}}); });
    EXPECT_NE(msg.find("empty name"), std::string::npos) << msg;
    EXPECT_EQ(slurp(path("keep.png")), png);
    EXPECT_EQ(slurp(path("keep.exr")), exr);

    const std::string nowhere = path("missing/dir/x.png");
    msg = message_of([&] { ltm::write_png(nowhere, img); });
    EXPECT_NE(msg.find("cannot write PNG image '" + nowhere + "': the folder '" + path("missing/dir") +
                       "' does not exist"),
              std::string::npos)
        << msg;
    msg = message_of([&] { ltm::write_exr(path("missing/y.exr"), 4, 4, {{"Y", img.data}}); });
    EXPECT_NE(msg.find("the folder '" + path("missing") + "' does not exist"), std::string::npos) << msg;
    EXPECT_EQ(listing(), (std::vector<std::string>{"keep.exr", "keep.png"}));
}

// ----- 16-bit masks -----

// Reads a PNG with libpng's low-level interface, without any transformation: the IHDR fields
// and the raw 16-bit samples (big-endian in the file) of a greyscale image.
struct RawPng16 {
    png_uint_32 width = 0, height = 0;
    int bit_depth = 0, color_type = -1, interlace = -1;
    std::vector<std::uint16_t> values;  // row-major, first stored row first
};
RawPng16 read_raw_png16(const std::string& file) {
    RawPng16 r;
    FILE* fp = std::fopen(file.c_str(), "rb");
    if (!fp) return r;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png))) std::abort();  // the file under test is broken: fail loudly
    png_init_io(png, fp);
    png_read_info(png, info);
    png_get_IHDR(png, info, &r.width, &r.height, &r.bit_depth, &r.color_type, &r.interlace, nullptr, nullptr);
    if (r.bit_depth == 16 && r.color_type == PNG_COLOR_TYPE_GRAY) {
        std::vector<png_byte> row(png_get_rowbytes(png, info));
        for (png_uint_32 y = 0; y < r.height; ++y) {
            png_read_row(png, row.data(), nullptr);
            for (png_uint_32 x = 0; x < r.width; ++x)
                r.values.push_back(static_cast<std::uint16_t>((row[2 * x] << 8) | row[2 * x + 1]));
        }
    }
    png_destroy_read_struct(&png, &info, nullptr);
    std::fclose(fp);
    return r;
}

TEST_F(ImageTest, Png16RoundTripsEveryValueWithRowZeroOnTop) {
    // 7 x 5 with distinct values per pixel, the extremes, and both bytes of a sample mattering.
    const int w = 7, h = 5;
    std::vector<std::uint16_t> v(static_cast<std::size_t>(w * h));
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<std::uint16_t>(i * 1873 + 11);
    v[0] = 0;
    v[1] = 1;
    v[2] = 255;
    v[3] = 256;
    v[4] = 65535;
    v[5] = 65534;
    v[static_cast<std::size_t>(w * h - 1)] = 65535;
    ltm::write_png16(path("mask.png"), w, h, v);
    EXPECT_EQ(listing(), std::vector<std::string>{"mask.png"});

    // The IHDR chunk in the file's bytes: after the signature, length 13, "IHDR", width, height,
    // then bit depth 16 and colour type 0 (greyscale).
    const std::string bytes = slurp(path("mask.png"));
    ASSERT_GE(bytes.size(), 33u);
    EXPECT_EQ(bytes.substr(12, 4), "IHDR");
    EXPECT_EQ(static_cast<unsigned char>(bytes[24]), 16);
    EXPECT_EQ(static_cast<unsigned char>(bytes[25]), 0);

    const RawPng16 r = read_raw_png16(path("mask.png"));
    EXPECT_EQ(r.width, static_cast<png_uint_32>(w));
    EXPECT_EQ(r.height, static_cast<png_uint_32>(h));
    EXPECT_EQ(r.bit_depth, 16);
    EXPECT_EQ(r.color_type, PNG_COLOR_TYPE_GRAY);
    EXPECT_EQ(r.interlace, PNG_INTERLACE_NONE);
    EXPECT_EQ(r.values, v);  // the first stored row is row 0

    // read_image scales 16-bit code values to [0, 1].
    const Image back = ltm::read_image(path("mask.png"));
    ASSERT_EQ(back.channels, 1);
    ASSERT_EQ(back.pixel_count(), v.size());
    for (std::size_t i = 0; i < v.size(); ++i) EXPECT_EQ(back.data[i], static_cast<float>(v[i]) / 65535.0f) << i;
}

TEST_F(ImageTest, Png16BadArgumentsAreRefusedAndTheTargetKept) {
    const std::vector<std::uint16_t> v(12, 7);
    ltm::write_png16(path("keep.png"), 4, 3, v);
    const std::string before = slurp(path("keep.png"));
    EXPECT_EQ(message_of([&] { ltm::write_png16(path("keep.png"), 5, 3, v); }),
              "cannot write PNG image '" + path("keep.png") + "': there are 12 values for 5 x 3 = 15 pixels");
    EXPECT_EQ(message_of([&] { ltm::write_png16(path("keep.png"), 0, 3, {}); }),
              "cannot write PNG image '" + path("keep.png") + "': the image is empty (0 x 3)");
    EXPECT_EQ(message_of([&] { ltm::write_png16(path("missing/m.png"), 4, 3, v); }),
              "cannot write PNG image '" + path("missing/m.png") + "': the folder '" + path("missing") +
                  "' does not exist");
    EXPECT_EQ(slurp(path("keep.png")), before);
    EXPECT_EQ(listing(), std::vector<std::string>{"keep.png"});
}

// ----- display pattern values -----

TEST(PatternValues, GrayIsUnchangedAndRgbIsRec709Luminance) {
    Image gray(3, 1, 1);
    gray.data = {0.0f, 0.5f, 7.0f};
    EXPECT_EQ(ltm::pattern_values(gray), gray.data);

    Image rgb(5, 1, 3);
    rgb.data = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 0.3f, 0.6f, 0.9f};
    const std::vector<float> y = ltm::pattern_values(rgb);
    ASSERT_EQ(y.size(), 5u);
    for (std::size_t i = 0; i < 5; ++i) {
        const double r = rgb.data[3 * i], g = rgb.data[3 * i + 1], b = rgb.data[3 * i + 2];
        const double expected = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        const double s = 0.2126 * std::fabs(r) + 0.7152 * std::fabs(g) + 0.0722 * std::fabs(b);
        EXPECT_NEAR(y[i], expected, ltm::tol::luminance(s)) << i;
    }
    EXPECT_NEAR(y[0], 0.2126, ltm::tol::luminance(0.2126));
    EXPECT_NEAR(y[1], 0.7152, ltm::tol::luminance(0.7152));
    EXPECT_NEAR(y[2], 0.0722, ltm::tol::luminance(0.0722));
    EXPECT_NEAR(y[3], 1.0, ltm::tol::luminance(1.0));

    Image two(2, 2, 2);
    EXPECT_THROW(ltm::pattern_values(two), std::invalid_argument);
}

// A header that declares a huge data window (what fuzz/fuzz_image found: a few changed bytes asked
// for 5 GB) is refused from the header alone, before any pixel buffer is allocated: the message
// names the declared size, not memory or truncation.
TEST_F(ImageTest, ExrDeclaringTooManyValuesIsRefusedBeforeAllocating) {
    ltm::write_exr(path("small.exr"), 4, 3, {{"Y", std::vector<float>(12, 0.5f)}});
    std::string exr = slurp(path("small.exr"));
    // dataWindow: name, type "box2i", size 16, then min.x, min.y, max.x, max.y (little-endian int32)
    const std::string key = std::string("dataWindow") + '\0' + "box2i" + '\0';
    const size_t at = exr.find(key);
    ASSERT_NE(at, std::string::npos);
    const size_t box = at + key.size() + 4;
    {  // 80 rows of 4 million pixels: five ZIP chunks (their offsets are read from what follows
        // the one real chunk's), rows OpenEXR itself accepts
        const std::int32_t x = 3999999, y = 79;
        std::memcpy(&exr[box + 8], &x, sizeof x);
        std::memcpy(&exr[box + 12], &y, sizeof y);
    }
    // OpenEXR scans the file for the chunks its offset table does not hold: zeros to scan
    spit(path("huge.exr"), exr + std::string(1 << 16, '\0'));
    const std::string msg = message_of([&] { ltm::read_image(path("huge.exr")); });
    EXPECT_NE(msg.find("cannot read image '" + path("huge.exr") + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("declares 4000000 x 80 pixels in 1 channels, more than the 268435456 values"),
              std::string::npos)
        << msg;
    // At the limit's side of it, a declared window that fits is read on (and is then truncated).
    {
        const std::int32_t v = 999;
        std::memcpy(&exr[box + 8], &v, sizeof v);
    }
    spit(path("big.exr"), exr);
    const std::string msg2 = message_of([&] { ltm::read_image(path("big.exr")); });
    EXPECT_EQ(msg2.find("values an image may hold"), std::string::npos) << msg2;
}
