#include "io/Image.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfCompression.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <png.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <sys/stat.h>

#include "io/AtomicFile.h"
#include "io/Deflate.h"
#include "io/Npz.h"

namespace ltm {

namespace {

struct ReadError : std::runtime_error {
    using std::runtime_error::runtime_error;
};
[[noreturn]] void bad(const std::string& what) { throw ReadError(what); }

const unsigned char kPngMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
const unsigned char kExrMagic[4] = {0x76, 0x2F, 0x31, 0x01};
// The most bytes write_png puts in one IDAT chunk (the format allows up to 2^31 - 1).
constexpr std::size_t kPngMaxIdat = 65536;

// The whole file, or its first `limit` bytes; throws ReadError for a missing, unreadable or
// empty file.
std::vector<unsigned char> read_bytes(const std::string& path, std::size_t limit = SIZE_MAX) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        const int e = errno;
        if (e == ENOENT) bad("no such file");
        bad(std::string("cannot access it: ") + std::strerror(e));
    }
    if (S_ISDIR(st.st_mode)) bad("it is a folder");
    std::ifstream in(path, std::ios::binary);
    if (!in) bad(std::string("cannot open it: ") + std::strerror(errno));
    std::vector<unsigned char> bytes;
    const auto size = static_cast<std::size_t>(std::max<off_t>(st.st_size, 0));
    bytes.resize(std::min(size, limit));
    in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (static_cast<std::size_t>(in.gcount()) != bytes.size()) bad("reading it failed");
    if (bytes.empty()) bad("the file is empty");
    return bytes;
}

bool starts_with(const std::vector<unsigned char>& b, const unsigned char* magic, std::size_t n) {
    return b.size() >= n && std::memcmp(b.data(), magic, n) == 0;
}

std::string describe_start(const std::vector<unsigned char>& b) {
    std::string s;
    char buf[8];
    for (std::size_t i = 0; i < std::min<std::size_t>(b.size(), 8); ++i) {
        std::snprintf(buf, sizeof buf, "%s%02x", i ? " " : "", b[i]);
        s += buf;
    }
    return s;
}

// ----- PNG read via libpng; libpng reports errors by longjmp, so the decoder keeps no C++ objects
// with destructors between setjmp and the libpng calls (only ones declared before setjmp). -----

struct PngIo {
    const unsigned char* data = nullptr;
    std::size_t size = 0, pos = 0;
    char message[512] = {};
};

void png_error_fn(png_structp png, png_const_charp msg) {
    auto* io = static_cast<PngIo*>(png_get_error_ptr(png));
    std::snprintf(io->message, sizeof io->message, "%s", msg ? msg : "unknown libpng error");
    png_longjmp(png, 1);
}
void png_warning_fn(png_structp, png_const_charp) {}

void png_read_fn(png_structp png, png_bytep out, png_size_t n) {
    auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
    if (n > io->size - io->pos) png_error(png, "the file is truncated (unexpected end of data)");
    std::memcpy(out, io->data + io->pos, n);
    io->pos += n;
}


// Writes the rows row(r, out) gives (top to bottom, r = 0 .. height - 1, each rowbytes = width *
// channels samples of bit_depth 8 or 16, 16-bit ones big-endian) to `path` as a PNG file,
// atomically (the PNG specification, ISO/IEC 15948): the signature; IHDR (width, height, bit
// depth, colour type; compression, filter and interlace methods 0); IDAT chunks holding the zlib
// stream (RFC 1950) of the rows, each row after its filter-type byte 0 (None: previews are flat
// colour and noisy data cells, which the adaptive filters do not predict; unfiltered rows deflated
// ~10 % smaller and ~35 % faster with libpng); IEND. Each chunk is its length, type, data and the
// CRC-32 of type and data. The rows are deflated by igzip (io/Deflate.h) at kPngLevel.
//
// A picture of up to kPngWholeBytes filtered bytes is laid out whole in a buffer the thread keeps
// (io::thread_buffer) and deflated in one call (zlib_deflate): igzip's streaming deflate copies
// every byte it is given into its history buffer first, which costs a tenth of a preview's time
// (perf, bench_features' BM_WriteFile/file:4). A larger picture is streamed a row at a time from
// one line, so that its copy is never made (a 16-bit frame of a large camera).

void write_png_file(const std::string& path, int width, int height, int bit_depth, int color_type, std::size_t rowbytes,
                    const std::function<void(int, std::uint8_t*)>& row, io::CommitGroup* group = nullptr) {
    // The limit: deflate's stored blocks need 5 bytes per 64 KiB and zlib 6 bytes of header and
    // Adler-32, but igzip's streaming deflate falls back to stored blocks only within one piece of
    // input, and on random rows it writes 0.065 % over the input (measured): the room is n / 64 +
    // 4 KiB over it, and costs nothing until written (io::ScratchBytes).
    const std::size_t n = (rowbytes + 1) * static_cast<std::size_t>(height);
    const std::size_t limit = n + n / 64 + 4096;
    io::Deflated z;
    try {
        if (n <= kPngWholeBytes) {
            unsigned char* const rows = io::thread_buffer(0, n);
            for (int r = 0; r < height; ++r) {
                unsigned char* const line = rows + static_cast<std::size_t>(r) * (rowbytes + 1);
                line[0] = 0;  // filter type None
                row(r, line + 1);
            }
            z = io::zlib_deflate(rows, n, kPngLevel, limit);
        } else {
            io::ZlibStream stream(kPngLevel, limit);
            unsigned char* const line = io::thread_buffer(0, rowbytes + 1);
            line[0] = 0;  // filter type None
            for (int r = 0; r < height; ++r) {
                row(r, line + 1);
                if (!stream.add(line, rowbytes + 1, r + 1 == height)) break;
            }
            z = stream.result();
        }
    } catch (const std::exception& e) {
        throw std::runtime_error("cannot write PNG image '" + path + "': " + e.what());
    }
    if (z.size == 0) throw std::runtime_error("cannot write PNG image '" + path + "': deflate did not fit in its worst-case size");
    io::AtomicFile file(path, "PNG image");
    file.write(kPngMagic, 8);
    const auto chunk = [&](const char* type, const unsigned char* data, std::size_t len) {
        unsigned char head[8], tail[4];
        for (int k = 0; k < 4; ++k) head[k] = static_cast<unsigned char>(len >> (24 - 8 * k));
        std::memcpy(head + 4, type, 4);
        const std::uint32_t crc = io::crc32(io::crc32(0, type, 4), data, len);
        for (int k = 0; k < 4; ++k) tail[k] = static_cast<unsigned char>(crc >> (24 - 8 * k));
        file.write(head, 8);
        file.write(data, len);
        file.write(tail, 4);
    };
    unsigned char ihdr[13] = {};
    for (int k = 0; k < 4; ++k) {
        ihdr[k] = static_cast<unsigned char>(static_cast<std::uint32_t>(width) >> (24 - 8 * k));
        ihdr[4 + k] = static_cast<unsigned char>(static_cast<std::uint32_t>(height) >> (24 - 8 * k));
    }
    ihdr[8] = static_cast<unsigned char>(bit_depth);
    ihdr[9] = static_cast<unsigned char>(color_type);  // ihdr[10..12]: methods 0
    chunk("IHDR", ihdr, sizeof ihdr);
    for (std::size_t at = 0; at < z.size; at += kPngMaxIdat)
        chunk("IDAT", z.data + at, std::min(kPngMaxIdat, z.size - at));
    chunk("IEND", nullptr, 0);
    file.commit(group);
}

// The same from `size` bytes of rows in memory.
void write_png_file(const std::string& path, int width, int height, int bit_depth, int color_type,
                    const unsigned char* samples, std::size_t size, io::CommitGroup* group = nullptr) {
    const std::size_t rowbytes = size / static_cast<std::size_t>(height);
    write_png_file(
        path, width, height, bit_depth, color_type, rowbytes,
        [&](int r, std::uint8_t* out) { std::memcpy(out, samples + static_cast<std::size_t>(r) * rowbytes, rowbytes); },
        group);
}

// Decodes into `pixels` (8 or 16-bit samples, 1 or 3 channels); false with io.message on error.
bool decode_png(PngIo& io, int& width, int& height, int& channels, int& depth, std::vector<unsigned char>& pixels,
                std::vector<png_bytep>& rows) {
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &io, png_error_fn, png_warning_fn);
    if (!png) {
        std::snprintf(io.message, sizeof io.message, "libpng could not be initialised");
        return false;
    }
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_read_struct(&png, nullptr, nullptr);
        std::snprintf(io.message, sizeof io.message, "libpng could not be initialised");
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        return false;
    }
    png_set_read_fn(png, &io, png_read_fn);
    png_read_info(png, info);
    const int color = png_get_color_type(png, info);
    const int bits = png_get_bit_depth(png, info);
    if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (color == PNG_COLOR_TYPE_GRAY && bits < 8) png_set_expand_gray_1_2_4_to_8(png);
    // libpng 1.6's palette expansion also turns a tRNS chunk into alpha: strip that too.
    if ((color & PNG_COLOR_MASK_ALPHA) || png_get_valid(png, info, PNG_INFO_tRNS)) png_set_strip_alpha(png);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    width = static_cast<int>(png_get_image_width(png, info));
    height = static_cast<int>(png_get_image_height(png, info));
    channels = png_get_channels(png, info);
    depth = png_get_bit_depth(png, info);
    if ((channels != 1 && channels != 3) || (depth != 8 && depth != 16))
        png_error(png, "unexpected pixel layout after conversion");
    const std::size_t rowbytes = png_get_rowbytes(png, info);
    if (rowbytes != static_cast<std::size_t>(width) * static_cast<std::size_t>(channels * depth / 8))
        png_error(png, "unexpected row size after conversion");
    pixels.resize(rowbytes * static_cast<std::size_t>(height));
    rows.resize(static_cast<std::size_t>(height));
    for (int r = 0; r < height; ++r) rows[static_cast<std::size_t>(r)] = pixels.data() + rowbytes * static_cast<std::size_t>(r);
    png_read_image(png, rows.data());
    png_read_end(png, nullptr);
    png_destroy_read_struct(&png, &info, nullptr);
    return true;
}

Image read_png_bytes(const std::vector<unsigned char>& bytes) {
    PngIo io;
    io.data = bytes.data();
    io.size = bytes.size();
    int width = 0, height = 0, channels = 0, depth = 0;
    std::vector<unsigned char> pixels;
    std::vector<png_bytep> rows;
    bool ok;
    try {
        ok = decode_png(io, width, height, channels, depth, pixels, rows);
    } catch (const std::bad_alloc&) {
        bad("PNG image too large for memory");
    }
    if (!ok) bad(std::string("corrupt or unsupported PNG (libpng: ") + io.message + ")");
    Image img(width, height, channels);
    const std::size_t n = img.data.size();
    if (depth == 8) {
        for (std::size_t i = 0; i < n; ++i) img.data[i] = static_cast<float>(pixels[i]) / 255.0f;
    } else {
        for (std::size_t i = 0; i < n; ++i)
            img.data[i] = static_cast<float>((pixels[2 * i] << 8) | pixels[2 * i + 1]) / 65535.0f;
    }
    return img;
}

// ----- OpenEXR -----

using Channels = std::vector<std::pair<std::string, std::vector<float>>>;

Channels read_exr_file(const std::string& path, int& width, int& height) {
    const std::vector<unsigned char> head = read_bytes(path, 4);
    if (!starts_with(head, kExrMagic, 4))
        bad("not an OpenEXR file (it starts with " + describe_start(head) + ", not 76 2f 31 01)");
    Channels out;
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        const std::int64_t w = std::int64_t(dw.max.x) - dw.min.x + 1, h = std::int64_t(dw.max.y) - dw.min.y + 1;
        if (w <= 0 || h <= 0 || w > INT32_MAX || h > INT32_MAX) bad("it has an empty or invalid data window");
        width = static_cast<int>(w);
        height = static_cast<int>(h);
        Imf::FrameBuffer fb;
        const Imf::ChannelList& list = file.header().channels();
        std::int64_t count = 0;
        for (auto it = list.begin(); it != list.end(); ++it) {
            if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                bad(std::string("channel '") + it.name() + "' is subsampled, which is not supported");
            ++count;
        }
        if (count == 0) bad("it has no channels");
        // Checked before anything is allocated: the header alone declares the size, and a few
        // corrupt bytes of it would otherwise ask for gigabytes (fuzz/fuzz_image reaches this).
        if (w * h > kMaxImageValues / count)
            bad("it declares " + std::to_string(w) + " x " + std::to_string(h) + " pixels in " + std::to_string(count) +
                " channels, more than the " + std::to_string(kMaxImageValues) + " values an image may hold");
        if (!file.isComplete()) bad("the file is truncated or incomplete (some pixels are missing)");
        for (auto it = list.begin(); it != list.end(); ++it)
            out.emplace_back(it.name(), std::vector<float>(static_cast<std::size_t>(w) * static_cast<std::size_t>(h)));
        for (auto& [name, values] : out)
            fb.insert(name.c_str(), Imf::Slice::Make(Imf::FLOAT, values.data(), dw, sizeof(float),
                                                     sizeof(float) * static_cast<std::size_t>(w)));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
    } catch (const ReadError&) {
        throw;
    } catch (const std::bad_alloc&) {
        bad("image too large for memory");
    } catch (const std::exception& e) {
        bad(std::string("corrupt or unsupported OpenEXR file (OpenEXR: ") + e.what() + ")");
    }
    return out;
}

Image exr_to_image(Channels channels, int width, int height) {
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    if (channels.size() == 1) {
        Image img;
        img.width = width;
        img.height = height;
        img.channels = 1;
        img.data = std::move(channels[0].second);
        return img;
    }
    const std::vector<float>* rgb[3] = {nullptr, nullptr, nullptr};
    for (const auto& [name, values] : channels) {
        if (name == "R") rgb[0] = &values;
        if (name == "G") rgb[1] = &values;
        if (name == "B") rgb[2] = &values;
    }
    if (!rgb[0] || !rgb[1] || !rgb[2]) {
        std::string names;
        for (const auto& c : channels) names += (names.empty() ? "" : ", ") + c.first;
        bad("it has the channels " + names + ": a pattern needs a single channel, or channels R, G and B");
    }
    Image img(width, height, 3);
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) img.data[3 * i + static_cast<std::size_t>(c)] = (*rgb[c])[i];
    return img;
}

// Appends v as 4 little-endian bytes (EXR's integers).
void put_le32(std::string& out, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFF));
}

// OpenEXR's ZIP_COMPRESSION: blocks of 16 scan lines, deflated in the zlib format. At igzip's
// level 2 the industrial scene's features.exr (1000 x 1000, 17 channels) is written in 0.21 s
// against OpenEXR's 0.92 s (its zlib at its default level 4), 3.6 % larger; levels 1 and 3 are
// slower here and no smaller (docs/benchmarks.md).
constexpr int kExrZipLines = 16;
constexpr int kExrZipLevel = 2;

}  // namespace

Image read_image(const std::string& path) {
    try {
        const std::vector<unsigned char> head = read_bytes(path, 8);
        if (starts_with(head, kPngMagic, 8)) return read_png_bytes(read_bytes(path));
        if (starts_with(head, kExrMagic, 4)) {
            int w = 0, h = 0;
            Channels channels = read_exr_file(path, w, h);  // OpenEXR reads the file itself
            return exr_to_image(std::move(channels), w, h);
        }
        bad("not a PNG or OpenEXR file (unrecognised content, it starts with " + describe_start(head) + ")");
    } catch (const ReadError& e) {
        throw std::runtime_error("cannot read image '" + path + "': " + e.what());
    }
}

std::vector<std::pair<std::string, std::vector<float>>> read_exr_channels(const std::string& path, int* width,
                                                                         int* height) {
    try {
        int w = 0, h = 0;
        Channels channels = read_exr_file(path, w, h);
        if (width) *width = w;
        if (height) *height = h;
        return channels;
    } catch (const ReadError& e) {
        throw std::runtime_error("cannot read EXR image '" + path + "': " + e.what());
    }
}

std::vector<float> pattern_values(const Image& img) {
    const std::size_t n = img.pixel_count();
    if (img.data.size() != n * static_cast<std::size_t>(std::max(img.channels, 0)))
        throw std::invalid_argument("pattern_values: the image's data size does not match its dimensions");
    if (img.channels == 1) return img.data;
    if (img.channels != 3)
        throw std::invalid_argument("pattern_values: a pattern image needs 1 or 3 channels, not " +
                                    std::to_string(img.channels));
    std::vector<float> y(n);
    for (std::size_t i = 0; i < n; ++i)
        y[i] = static_cast<float>(0.2126 * img.data[3 * i] + 0.7152 * img.data[3 * i + 1] + 0.0722 * img.data[3 * i + 2]);
    return y;
}

namespace {
// What an 8-bit PNG of an Image or Image8 needs of its shape; throws naming the file.
template <class Picture>
void check_8bit_picture(const Picture& img, const std::string& path) {
    auto fail = [&](const std::string& why) { throw std::runtime_error("cannot write PNG image '" + path + "': " + why); };
    if (img.width <= 0 || img.height <= 0)
        fail("the image is empty (" + std::to_string(img.width) + " x " + std::to_string(img.height) + ")");
    if (img.channels != 1 && img.channels != 3)
        fail("the image has " + std::to_string(img.channels) + " channels; PNG output needs 1 (gray) or 3 (RGB)");
    if (img.data.size() != img.pixel_count() * static_cast<std::size_t>(img.channels))
        fail("the image's data size " + std::to_string(img.data.size()) + " does not match " + std::to_string(img.width) +
             " x " + std::to_string(img.height) + " x " + std::to_string(img.channels));
}
}  // namespace

void write_png(const std::string& path, const Image& img, io::CommitGroup* group) {
    auto fail = [&](const std::string& why) { throw std::runtime_error("cannot write PNG image '" + path + "': " + why); };
    check_8bit_picture(img, path);
    Image8 codes;
    codes.width = img.width;
    codes.height = img.height;
    codes.channels = img.channels;
    codes.data.resize(img.data.size());
    for (std::size_t i = 0; i < codes.data.size(); ++i) {
        const float v = img.data[i];
        if (std::isnan(v)) {
            const std::size_t px = i / static_cast<std::size_t>(img.channels);
            fail("the value at row " + std::to_string(px / static_cast<std::size_t>(img.width)) + ", column " +
                 std::to_string(px % static_cast<std::size_t>(img.width)) + " is NaN");
        }
        codes.data[i] = png_code(v);
    }
    write_png(path, codes, group);
}

void write_png(const std::string& path, const Image8& img, io::CommitGroup* group) {
    check_8bit_picture(img, path);
    write_png_file(path, img.width, img.height, 8, img.channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB,
                   img.data.data(), img.data.size(), group);
}

void write_png_rows(const std::string& path, int width, int height, int channels,
                    const std::function<void(int, std::uint8_t*)>& row, io::CommitGroup* group) {
    auto fail = [&](const std::string& why) { throw std::runtime_error("cannot write PNG image '" + path + "': " + why); };
    if (width <= 0 || height <= 0)
        fail("the image is empty (" + std::to_string(width) + " x " + std::to_string(height) + ")");
    if (channels != 1 && channels != 3)
        fail("the image has " + std::to_string(channels) + " channels; PNG output needs 1 (gray) or 3 (RGB)");
    write_png_file(path, width, height, 8, channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB,
                   static_cast<std::size_t>(width) * static_cast<std::size_t>(channels), row, group);
}

void write_png16(const std::string& path, int width, int height, const std::vector<std::uint16_t>& values) {
    auto fail = [&](const std::string& why) { throw std::runtime_error("cannot write PNG image '" + path + "': " + why); };
    if (width <= 0 || height <= 0)
        fail("the image is empty (" + std::to_string(width) + " x " + std::to_string(height) + ")");
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    if (values.size() != n)
        fail("there are " + std::to_string(values.size()) + " values for " + std::to_string(width) + " x " +
             std::to_string(height) + " = " + std::to_string(n) + " pixels");
    std::vector<unsigned char> samples(2 * n);  // PNG stores 16-bit samples big-endian
    for (std::size_t i = 0; i < n; ++i) {
        samples[2 * i] = static_cast<unsigned char>(values[i] >> 8);
        samples[2 * i + 1] = static_cast<unsigned char>(values[i] & 0xFF);
    }
    write_png_file(path, width, height, 16, PNG_COLOR_TYPE_GRAY, samples.data(), samples.size());
}

void write_exr(const std::string& path, int width, int height,
               const std::vector<std::pair<std::string, std::vector<float>>>& channels, io::CommitGroup* group) {
    std::vector<ExrChannelView> views;
    views.reserve(channels.size());
    for (const auto& [name, values] : channels) views.push_back({name, values.data(), values.size(), 1});
    write_exr(path, width, height, views, group);
}

void write_exr(const std::string& path, int width, int height, const std::vector<ExrChannelView>& channels,
               io::CommitGroup* group) {
    auto fail = [&](const std::string& why) { throw std::runtime_error("cannot write EXR image '" + path + "': " + why); };
    if (width <= 0 || height <= 0)
        fail("the image is empty (" + std::to_string(width) + " x " + std::to_string(height) + ")");
    if (channels.empty()) fail("no channels given");
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    std::set<std::string> names;
    for (const ExrChannelView& c : channels) {
        if (c.name.empty()) fail("a channel has an empty name");
        if (c.name.size() > 255) fail("the channel name '" + c.name + "' is longer than 255 characters");
        if (!names.insert(c.name).second) fail("two channels are named '" + c.name + "'");
        if (c.count != n)
            fail("channel '" + c.name + "' has " + std::to_string(c.count) + " values, expected " +
                 std::to_string(width) + " x " + std::to_string(height) + " = " + std::to_string(n));
        if (c.stride == 0 || (n > 0 && !c.values)) fail("channel '" + c.name + "' has no values");
    }
    // A block's size is a 32-bit signed integer in the file.
    if (static_cast<double>(kExrZipLines) * static_cast<double>(width) * 4.0 * static_cast<double>(channels.size()) >
        2147483647.0)
        fail("the image is too wide for EXR's blocks of 16 scan lines (" + std::to_string(width) + " pixels, " +
             std::to_string(channels.size()) + " channels)");
    // The channels in the file's order: sorted by name, byte by byte (OpenEXR's ChannelList).
    std::vector<const ExrChannelView*> sorted;
    for (const auto& c : channels) sorted.push_back(&c);
    std::sort(sorted.begin(), sorted.end(), [](const auto* a, const auto* b) { return a->name < b->name; });

    // The header (the attributes Imf::Header(width, height) gives, in OpenEXR's alphabetical
    // order, with ZIP compression), then the line offset table, then the blocks.
    std::string head("\x76\x2f\x31\x01", 4);  // magic number
    bool long_names = false;
    for (const auto* c : sorted) long_names = long_names || c->name.size() > 31;
    put_le32(head, 2u | (long_names ? 0x400u : 0u));  // version 2, single-part scan lines
    const auto attribute = [&](const char* name, const char* type, const std::string& value) {
        head += name;
        head += '\0';
        head += type;
        head += '\0';
        put_le32(head, static_cast<std::uint32_t>(value.size()));
        head += value;
    };
    std::string chlist, window, one, centre;
    for (const auto* c : sorted) {
        chlist += c->name;
        chlist += '\0';
        put_le32(chlist, 2);                  // pixel type FLOAT
        chlist += std::string(4, '\0');       // pLinear 0, three reserved bytes
        put_le32(chlist, 1);                  // x sampling
        put_le32(chlist, 1);                  // y sampling
    }
    chlist += '\0';
    for (int v : {0, 0, width - 1, height - 1}) put_le32(window, static_cast<std::uint32_t>(v));
    put_le32(one, 0x3F800000u);  // 1.0f
    put_le32(centre, 0);
    put_le32(centre, 0);
    attribute("channels", "chlist", chlist);
    attribute("compression", "compression", std::string(1, '\x03'));  // ZIP_COMPRESSION
    attribute("dataWindow", "box2i", window);
    attribute("displayWindow", "box2i", window);
    attribute("lineOrder", "lineOrder", std::string(1, '\0'));  // INCREASING_Y
    attribute("pixelAspectRatio", "float", one);
    attribute("screenWindowCenter", "v2f", centre);
    attribute("screenWindowWidth", "float", one);
    head += '\0';

    // The blocks of 16 scan lines (ZIP_COMPRESSION's), each: its first y, its size, its bytes.
    // A block's pixel bytes are, line by line, each channel's floats of that line (little-endian,
    // x increasing). OpenEXR's ZIP (ImfZip.cpp) splits them into the even-indexed bytes followed by
    // the odd-indexed ones, replaces each byte after the first by its difference from the one
    // before plus 128 (mod 256), and deflates that in the zlib format; a block that does not get
    // smaller is stored as its pixel bytes, which the reader recognises by their size.
    const int blocks = (height + kExrZipLines - 1) / kExrZipLines;
    const std::size_t row = static_cast<std::size_t>(width) * 4;
    io::AtomicFile file(path, "EXR image");
    file.write(head);
    // The line offset table (each block's position in the file) is written once the blocks are.
    const std::uint64_t table_at = file.tell();
    file.write(std::string(8 * static_cast<std::size_t>(blocks), '\0'));
    std::string table, frame;
    for (int b = 0; b < blocks; ++b) {
        const int y0 = b * kExrZipLines, lines = std::min(kExrZipLines, height - y0);
        const std::size_t size = static_cast<std::size_t>(lines) * sorted.size() * row;
        unsigned char* const pixels = io::thread_buffer(0, size);
        unsigned char* p = pixels;
        for (int y = y0; y < y0 + lines; ++y)
            for (const auto* c : sorted) {
                const float* v = c->values + static_cast<std::size_t>(y) * static_cast<std::size_t>(width) * c->stride;
                if (io::detail::kHostLittle && c->stride == 1) {
                    std::memcpy(p, v, row);
                    p += row;
                } else {
                    for (int x = 0; x < width; ++x, p += 4) {
                        std::uint32_t u;
                        std::memcpy(&u, v + static_cast<std::size_t>(x) * c->stride, 4);
                        for (int k = 0; k < 4; ++k) p[k] = static_cast<unsigned char>(u >> (8 * k));
                    }
                }
            }
        // The split and the differences in one pass: split[j] is the j-th byte of the even-indexed
        // bytes followed by the odd-indexed ones, stored as its difference from split[j - 1] + 128.
        unsigned char* const split = io::thread_buffer(1, size);
        const std::size_t half = (size + 1) / 2;
        split[0] = pixels[0];
        for (std::size_t j = 1; j < half; ++j)
            split[j] = static_cast<unsigned char>(pixels[2 * j] - pixels[2 * j - 2] + 128);
        if (half < size) split[half] = static_cast<unsigned char>(pixels[1] - pixels[2 * (half - 1)] + 128);
        for (std::size_t j = half + 1; j < size; ++j)
            split[j] = static_cast<unsigned char>(pixels[2 * (j - half) + 1] - pixels[2 * (j - half) - 1] + 128);
        io::Deflated deflated;
        try {
            deflated = io::zlib_deflate(split, size, kExrZipLevel, size);
        } catch (const std::exception& e) {
            file.fail(e.what());
        }
        const bool smaller = deflated.size > 0;
        const std::uint64_t at = file.tell();
        put_le32(table, static_cast<std::uint32_t>(at));
        put_le32(table, static_cast<std::uint32_t>(at >> 32));
        frame.clear();
        put_le32(frame, static_cast<std::uint32_t>(y0));
        put_le32(frame, static_cast<std::uint32_t>(smaller ? deflated.size : size));
        file.write(frame);
        file.write(smaller ? deflated.data : pixels, smaller ? deflated.size : size);
    }
    file.seek(table_at);
    file.write(table);
    file.commit(group);
}

void write_npz_channels(const std::string& path, int width, int height,
                        const std::vector<std::pair<std::string, std::vector<float>>>& channels, io::CommitGroup* group) {
    const auto n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    std::vector<io::NpyArray> arrays;
    for (const auto& [name, values] : channels) {
        if (values.size() != n)
            throw std::invalid_argument("write_npz_channels: channel '" + name + "' has " + std::to_string(values.size()) +
                                        " values, expected " + std::to_string(n));
        arrays.push_back(io::npy_array(name, values, {static_cast<std::uint64_t>(height), static_cast<std::uint64_t>(width)}));
    }
    io::NpzWriteOptions options;
    options.group = group;
    io::write_npz(path, arrays, options, "npz image");
}

}  // namespace ltm
