#pragma once
// Writing named dense arrays as a NumPy .npz archive: `numpy.load(path)` returns them, with the
// dtypes and shapes given here (numpy.savez_compressed's format).
//
//   std::vector<float> depth(h * w);  std::vector<std::uint16_t> mask(h * w);
//   io::write_npz(out + "/sample.npz", {io::npy_array("depth", depth, {h, w}),
//                                        io::npy_array("mask", mask, {h, w})});
//
// What write_npz writes (byte-for-byte deterministic: the same arrays and options always give the
// same file, whatever the machine, as long as zlib's deflate is the same version):
//   A ZIP archive with one entry "<name>.npy" per array, in the order given. Each entry is
//   deflate-compressed (ZIP method 8, raw zlib stream, level 6 by default as
//   numpy.savez_compressed) with its CRC-32, a fixed timestamp (1980-01-01 00:00) and no extra
//   attributes. Each .npy is format version 1.0: "\x93NUMPY" 1 0, a little-endian uint16 header
//   length, and the header "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }" padded
//   with spaces and ended by '\n' so that the preamble is a multiple of 64 bytes (as numpy pads
//   it); the array's bytes follow in C order (the last index varies fastest), in the byte order
//   the descr states.
//   ZIP64: an entry whose size (or worst-case compressed size, zlib's deflateBound) reaches
//   0xFFFFFFFF bytes gets ZIP64 size fields in its local and central headers; an entry starting
//   at or beyond 4 GiB gets a ZIP64 offset; an archive whose central directory lies beyond 4 GiB
//   (or with 65535 entries or more) ends with a ZIP64 end-of-central-directory record and
//   locator. So archives above 4 GiB are written in full (APPNOTE 6.3, as Python's zipfile reads).
//   NpzWriteOptions::force_zip64 writes every ZIP64 field even for small files (for tests).
// Writing is atomic (io/AtomicFile.h): the archive is streamed into a temporary file beside
// `path` and renamed onto it once complete; on any failure `path` is left as it was.
//
// Supported dtypes (NpyArray::descr, numpy's array-protocol strings): byte order '<' (little) or
// '>' (big) for multi-byte numbers, '|' for single bytes and byte strings; kinds
//   b1        bool (one byte, 0 or 1)
//   i1 i2 i4 i8, u1 u2 u4 u8   signed and unsigned integers
//   f2 f4 f8  IEEE floats
//   S<n>      byte strings of n >= 1 bytes (numpy's bytes_, e.g. "|S3" for b'csr')
// NpyArray::data holds the elements in the HOST's byte order (as they sit in memory); they are
// converted to the descr's order while writing (a no-op for '<' on little-endian hosts).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace ltm::io {

namespace detail {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
inline constexpr bool kHostLittle = true;
#else
inline constexpr bool kHostLittle = false;
#endif
template <class T>
constexpr bool negative(T v) {
    if constexpr (std::is_signed_v<T>) return v < T{};
    else return false;
}
}  // namespace detail

struct NpzWriteOptions {
    int compression_level = 6;  // zlib level 0..9 (0: deflate with stored blocks)
    bool force_zip64 = false;   // ZIP64 fields in every header and a ZIP64 end record
};

// Receives the bytes of an array as they go into the file, in pieces of any size.
using NpySink = std::function<void(const void* bytes, std::size_t n)>;

// One dense array, not owning its data (which must outlive the write_npz call).
struct NpyArray {
    std::string name;                   // numpy.load(path)[name]; the archive entry is name + ".npy"
    std::string descr;                  // dtype, see above: "<f4", "<i4", "<i8", "|u1", "<u2", "|S3" ...
    std::vector<std::uint64_t> shape;   // C order; {} is a scalar (one element)
    const void* data = nullptr;         // product(shape) elements, host byte order
    std::size_t bytes = 0;              // must equal product(shape) * itemsize
    // Instead of `data` (when set): produces the array's `bytes` bytes exactly as the file holds
    // them (in the descr's byte order), by calls of the sink; for data converted or generated on
    // the fly without a copy in memory. An exception it throws fails the write, with the array
    // named in the message.
    std::function<void(const NpySink&)> produce;
};

// The descr of a C++ element type: float "<f4", double "<f8", std::int8_t "|i1", std::uint8_t
// "|u1", std::int16_t "<i2", std::uint16_t "<u2", std::int32_t "<i4", std::uint32_t "<u4",
// std::int64_t "<i8", std::uint64_t "<u8" (a bool array, "|b1", needs an NpyArray by hand:
// std::vector<bool> has no contiguous storage).
template <class T>
constexpr const char* npy_descr() {
    if constexpr (std::is_same_v<T, float>) return "<f4";
    else if constexpr (std::is_same_v<T, double>) return "<f8";
    else if constexpr (std::is_same_v<T, std::int8_t>) return "|i1";
    else if constexpr (std::is_same_v<T, std::uint8_t>) return "|u1";
    else if constexpr (std::is_same_v<T, std::int16_t>) return "<i2";
    else if constexpr (std::is_same_v<T, std::uint16_t>) return "<u2";
    else if constexpr (std::is_same_v<T, std::int32_t>) return "<i4";
    else if constexpr (std::is_same_v<T, std::uint32_t>) return "<u4";
    else if constexpr (std::is_same_v<T, std::int64_t>) return "<i8";
    else if constexpr (std::is_same_v<T, std::uint64_t>) return "<u8";
    else static_assert(sizeof(T) == 0, "no npy dtype for this element type");
}

// An array viewing `values` (not copied: keep `values` alive and unchanged until written) with
// the given shape (product(shape) must equal values.size(); write_npz checks it), or 1-D.
template <class T>
NpyArray npy_array(std::string name, const std::vector<T>& values, std::vector<std::uint64_t> shape) {
    return NpyArray{std::move(name), npy_descr<T>(), std::move(shape), values.data(), values.size() * sizeof(T), {}};
}
template <class T>
NpyArray npy_array(std::string name, const std::vector<T>& values) {
    return npy_array(std::move(name), values, {static_cast<std::uint64_t>(values.size())});
}

// An array of dtype npy_descr<Out>() holding `values` converted to Out one by one while writing,
// in blocks of 1 MiB (no converted copy is ever held whole): e.g. int64 indices stored as int32.
// Integer values that do not survive the conversion exactly fail the write (naming the array, the
// value and its index); a conversion to float rounds as static_cast does. Views `values` like
// npy_array.
template <class Out, class In>
NpyArray npy_converted(std::string name, const std::vector<In>& values, std::vector<std::uint64_t> shape) {
    const In* v = values.data();
    const std::size_t n = values.size();
    const std::string descr = npy_descr<Out>();
    auto produce = [v, n, descr](const NpySink& sink) {
        constexpr std::size_t per = (std::size_t(1) << 20) / sizeof(Out);
        std::vector<unsigned char> buf(std::min(n, per) * sizeof(Out));
        for (std::size_t start = 0; start < n; start += per) {
            const std::size_t m = std::min(per, n - start);
            for (std::size_t i = 0; i < m; ++i) {
                const In x = v[start + i];
                const Out y = static_cast<Out>(x);
                if constexpr (std::is_integral_v<Out>) {
                    if (static_cast<In>(y) != x || detail::negative(x) != detail::negative(y))
                        throw std::range_error("value " + std::to_string(x) + " at index " + std::to_string(start + i) +
                                               " does not fit '" + descr + "'");
                }
                unsigned char raw[sizeof(Out)];
                std::memcpy(raw, &y, sizeof(Out));
                for (std::size_t b = 0; b < sizeof(Out); ++b)
                    buf[i * sizeof(Out) + b] = detail::kHostLittle ? raw[b] : raw[sizeof(Out) - 1 - b];
            }
            sink(buf.data(), m * sizeof(Out));
        }
    };
    NpyArray a{std::move(name), descr, std::move(shape), nullptr, n * sizeof(Out), {}};
    a.produce = std::move(produce);
    return a;
}
template <class Out, class In>
NpyArray npy_converted(std::string name, const std::vector<In>& values) {
    return npy_converted<Out>(std::move(name), values, {static_cast<std::uint64_t>(values.size())});
}

// A byte-string scalar of dtype "|S<n>", n = bytes.size() >= 1 (numpy.load gives numpy.bytes_).
// Views `bytes` like npy_array.
NpyArray npy_bytes_scalar(std::string name, const std::string& bytes);

// Writes the arrays to `path` (see above). Everything is checked before any file is touched:
// names (non-empty, distinct), descrs (supported), sizes (bytes = product(shape) * itemsize) and
// the compression level. Errors are std::runtime_error "cannot write <kind> '<path>': <reason>",
// naming the array where one is at fault.
void write_npz(const std::string& path, const std::vector<NpyArray>& arrays, const NpzWriteOptions& options = {},
               const std::string& kind = "npz archive");

}  // namespace ltm::io
