#pragma once
// Images in and out: display patterns read from PNG or OpenEXR, previews written as 8-bit PNG,
// masks as 16-bit greyscale PNG, feature images written as multi-channel float OpenEXR.
//
// Orientation (docs: docs/conventions.md): row 0 of an Image is the +y (top) edge of the
// picture, column 0 the -x (left) edge; this is also the first row stored in a PNG and the first
// scan line (lowest y of the data window) of an EXR, so a file looks the same in any viewer as
// the camera or display sees it. For a display pattern, Image row p, column q is display pixel
// (p, q), linear index l = p * Q + q (pattern_values gives exactly this flattening).
//
// Errors: every function that reads or writes a file throws std::runtime_error whose message
// names the file and what is wrong (missing, empty, truncated, corrupt, unsupported kind, bad arguments). Writers are atomic
// (io/AtomicFile.h): a failed write leaves an existing file untouched and no temporary behind.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace ltm::io {
class CommitGroup;  // io/AtomicFile.h
}

namespace ltm {

struct Image {
    int width = 0, height = 0, channels = 1;
    std::vector<float> data;  // row-major, row 0 = the +y (top) edge, channels interleaved

    Image() = default;
    Image(int width_, int height_, int channels_ = 1)  // all zeros
        : width(width_), height(height_), channels(channels_),
          data(static_cast<std::size_t>(width_ > 0 ? width_ : 0) * static_cast<std::size_t>(height_ > 0 ? height_ : 0) *
               static_cast<std::size_t>(channels_ > 0 ? channels_ : 0)) {}

    std::size_t index(int row, int col, int ch = 0) const {
        return (static_cast<std::size_t>(row) * static_cast<std::size_t>(width) + static_cast<std::size_t>(col)) *
                   static_cast<std::size_t>(channels) +
               static_cast<std::size_t>(ch);
    }
    float& at(int row, int col, int ch = 0) { return data[index(row, col, ch)]; }
    float at(int row, int col, int ch = 0) const { return data[index(row, col, ch)]; }
    std::size_t pixel_count() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
};

// An 8-bit picture as a PNG stores it: `channels` code values per pixel (1: gray, 3: RGB),
// row-major, row 0 on top. Previews are drawn straight into one (features/Plot.h): the float
// Image of the same picture takes four times the memory, and clearing and converting it would be
// most of a preview's cost.
struct Image8 {
    int width = 0, height = 0, channels = 1;
    std::vector<std::uint8_t> data;  // row-major, row 0 = the top row, channels interleaved

    Image8() = default;
    Image8(int width_, int height_, int channels_ = 1)  // all zeros
        : width(width_), height(height_), channels(channels_),
          data(static_cast<std::size_t>(width_ > 0 ? width_ : 0) * static_cast<std::size_t>(height_ > 0 ? height_ : 0) *
               static_cast<std::size_t>(channels_ > 0 ? channels_ : 0)) {}

    std::size_t pixel_count() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
};

// The 8-bit code value of v in [0, 1] as write_png stores it: v clamped to [0, 1], then
// round(255 v), half up. floor(x + 0.5) is that rounding here: x = 255 v has at most 32
// significant bits (a float times 255), so x + 0.5 is exact in double. k / 255 gives k.
// NaN has no code value: callers reject it first (write_png names the pixel).
inline std::uint8_t png_code(float v) {
    return static_cast<std::uint8_t>(std::clamp(static_cast<double>(v), 0.0, 1.0) * 255.0 + 0.5);
}

// Reads a PNG or an OpenEXR file, recognised by its first bytes (never by the extension).
//  PNG (libpng): 1, 2, 4, 8 and 16-bit; gray, gray + alpha, RGB, RGBA and palette images; the
//    result has 1 channel (gray) or 3 (RGB; palette images are expanded to RGB). Values are the
//    stored code values scaled to [0, 1] (v / 255, v / 65535, low bit depths as libpng expands
//    them to 8 bits); no gamma or colour-profile conversion is applied, and alpha is dropped.
//  OpenEXR: scan-line or tiled (level 0), first part; channels of any pixel type (HALF, FLOAT,
//    UINT are converted to float) without subsampling. A file with a single channel gives a 1-channel
//    image (whatever its name); otherwise it must have channels R, G and B, which give a
//    3-channel image in that order (other channels, e.g. A, are ignored); anything else is an
//    error listing the file's channels. Values are taken as stored (they may exceed [0, 1]).
// An OpenEXR file whose header declares more than kMaxImageValues values (pixels times channels,
// 2^28: 1 GiB of floats, e.g. a 16384 x 16384 single-channel or 8192 x 8192 RGBA image) is an
// error, found before anything is allocated.
Image read_image(const std::string& path);
inline constexpr std::int64_t kMaxImageValues = std::int64_t{1} << 28;

// The single float value per pixel a display pattern needs, in pixel order (row-major from the
// top row): 1 channel: the values as they are; 3 channels: the Rec. 709 / sRGB relative luminance
// Y = 0.2126 R + 0.7152 G + 0.0722 B (ITU-R BT.709 primaries, weights summing to 1), evaluated
// in double on the stored values and rounded to float. Other channel counts are an error
// (std::invalid_argument).
std::vector<float> pattern_values(const Image& img);

// An 8-bit PNG: gray for 1 channel, RGB for 3 channels (other counts are an error). Each value is
// stored as png_code(v): clamped to [0, 1] and rounded to round(255 v) (so k / 255 is written as
// k exactly); NaN is an error. Atomic. The file is written by io/Image.cpp itself (IHDR, IDAT
// chunks of the unfiltered rows, IEND), deflated by igzip (io/Deflate.h) at its level kPngLevel:
// previews are written with every render. Encoding and writing the 17 previews of the industrial
// scene (scenes/scale.yaml, 1000 x 1000 each) took 0.82 s through libpng and zlib at level 3, and
// takes 0.12 s, for 9.8 MB instead of 8.6 (the default scene's: 45 -> 16 ms, 507 -> 539 kB);
// igzip's level 1 is no faster and level 3 slower (one thread, best of 5 writes of the 17 pictures).
inline constexpr int kPngLevel = 2;
// A picture of up to this many bytes of rows (each after its filter byte) is deflated whole from
// one buffer its thread keeps; a larger one is streamed a row at a time (io/Image.cpp says why).
inline constexpr std::size_t kPngWholeBytes = std::size_t{32} << 20;
void write_png(const std::string& path, const Image& img, io::CommitGroup* group = nullptr);
// The same for code values as they are (png_code's); the same file as write_png of the Image
// whose values are these codes / 255.
void write_png(const std::string& path, const Image8& img, io::CommitGroup* group = nullptr);
// The same file as write_png of an 8-bit picture of `channels` (1 or 3) code values, its rows
// produced on demand: row(r, out) writes row r's width * channels codes to out (r from 0, the
// top, to height - 1, once each, in order). For a picture held in another layout, which then
// need not be copied whole into an Image8 first (a preview drawn in a Cairo surface).
// With `group`, the file is committed into it (io/AtomicFile.h's CommitGroup: in place at
// group->commit()), as write_png's and the EXR and npz files' below.
void write_png_rows(const std::string& path, int width, int height, int channels,
                    const std::function<void(int, std::uint8_t*)>& row, io::CommitGroup* group = nullptr);

// A 16-bit greyscale PNG (e.g. an instance mask: 0 = background, k = instance k), width x height
// values in Image order (row 0 = the top row of the picture). Each value is stored exactly as its
// 16-bit code value (no scaling: read_image gives v / 65535). Atomic.
void write_png16(const std::string& path, int width, int height, const std::vector<std::uint16_t>& values);

// An OpenEXR file with one 32-bit FLOAT channel per entry, named exactly as given (e.g.
// "BrightField", "ScatterCount"), each holding width * height values in Image order (row 0 on
// top). Scan lines in increasing y, ZIP compression (lossless, 16 lines per block), data and
// display windows (0, 0) - (width - 1, height - 1): the header Imf::Header(width, height) gives,
// with ZIP. Names must be non-empty and distinct. Written byte by byte into an io::AtomicFile
// (the OpenEXR file layout, as OpenEXR writes it, with each block deflated by igzip, io/Deflate.h,
// instead of OpenEXR's zlib: four times as fast), read back by OpenEXR in the
// tests. Atomic.
void write_exr(const std::string& path, int width, int height,
               const std::vector<std::pair<std::string, std::vector<float>>>& channels,
               io::CommitGroup* group = nullptr);
// The same from channels the caller holds elsewhere, without copying them: channel k's value at
// pixel i is values[i * stride] (stride 2 writes the two halves of an interleaved x, y array);
// count is how many pixels `values` holds, checked against width * height.
struct ExrChannelView {
    std::string name;
    const float* values = nullptr;
    std::size_t count = 0;
    std::size_t stride = 1;
};
void write_exr(const std::string& path, int width, int height, const std::vector<ExrChannelView>& channels,
               io::CommitGroup* group = nullptr);

// The same channels as a numpy .npz archive (io/Npz.h): one float32 array of shape (height,
// width) per channel, named as the channel, in C order (row 0 on top), so that numpy reads an
// image without an EXR library: numpy.load(path)["BrightField"]. Deflate at
// io/Npz.h's default level. Atomic.
void write_npz_channels(const std::string& path, int width, int height,
                        const std::vector<std::pair<std::string, std::vector<float>>>& channels,
                        io::CommitGroup* group = nullptr);

// Every channel of an OpenEXR file (see read_image for what is accepted), converted to float, in
// the file's channel order, which OpenEXR always stores sorted by name (so the order written by
// write_exr is not kept, only the names). width and height receive the data window's size
// (may be null).
std::vector<std::pair<std::string, std::vector<float>>> read_exr_channels(const std::string& path, int* width,
                                                                         int* height);

}  // namespace ltm
