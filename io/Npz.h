#pragma once
// Writing named dense arrays as a NumPy .npz archive: `numpy.load(path)` returns them, with the
// dtypes and shapes given here (numpy.savez_compressed's format).
//
//   std::vector<float> depth(h * w);  std::vector<std::uint16_t> mask(h * w);
//   io::write_npz(out + "/sample.npz", {io::npy_array("depth", depth, {h, w}),
//                                        io::npy_array("mask", mask, {h, w})});
//
// What write_npz writes (byte-for-byte deterministic: the same arrays and options always give the
// same file, whatever the thread or the run, with the same versions of libzip and ISA-L on the
// same kind of CPU; ISA-L picks its deflate kernels by the CPU's instruction sets, so on another
// kind the deflated bytes may differ, never the arrays they inflate to):
//   A ZIP archive, written by libzip, with one entry "<name>.npy" per array, in the order given.
//   Each entry is deflate-compressed (ZIP method 8, a raw deflate stream from ISA-L's igzip,
//   level 2 of its 1..3 by default, chosen by measurement in io/LtmFile.h; level 0 stores it
//   instead, ZIP method 0) with its CRC-32, a fixed timestamp (1980-01-01 00:00, DOS date 0x0021
//   time 0), no extra fields and no comments; otherwise libzip's defaults for a new entry ("made
//   by" Unix, version 6.3, file mode 0100666 in the external attributes; `zipinfo -v` shows all).
//   Each .npy is format version 1.0 (io/Npy.h): "\x93NUMPY" 1 0, a little-endian uint16 header
//   length, and the header "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }" padded
//   with spaces and ended by '\n' so that the preamble is a multiple of 64 bytes (as numpy pads
//   it); the array's bytes follow in C order (the last index varies fastest), in the byte order
//   the descr states.
//   ZIP64 where needed: a deflated entry of 4e9 bytes or more, or a stored one beyond 0xFFFFFFFF,
//   gets ZIP64 sizes in its local header (Npz.cpp, kZip64Entry); sizes or offsets beyond
//   0xFFFFFFFF get ZIP64 fields in the central directory, which then ends with a ZIP64
//   end-of-central-directory record and locator (also with 65535 entries or more). So archives
//   above 4 GiB are written in full (APPNOTE 6.3, as Python's zipfile and numpy read them). Small
//   archives have no ZIP64 fields.
//   No arrays at all give the 22-byte empty ZIP archive (an end record only).
// Writing is atomic (io/AtomicFile.h): libzip writes the archive through a custom write source
// into an AtomicFile (streaming; see Npz.cpp), which is renamed onto `path` once libzip has
// completed it; on any failure `path` is left as it was.
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

class CommitGroup;  // io/AtomicFile.h

struct NpzWriteOptions {
    int compression_level = 2;  // igzip level 1..3 for deflate; 0 stores the entries (ZIP method 0)
    CommitGroup* group = nullptr;  // committed into it (io/AtomicFile.h) instead of alone
};

// Fills `out` with the array's bytes [offset, offset + n) as the file holds them and returns how
// many it wrote: n, or fewer where the array's data ends.
using NpyFill = std::function<std::size_t(std::uint64_t offset, void* out, std::size_t n)>;

// One dense array, not owning its data (which must outlive the write_npz call).
struct NpyArray {
    std::string name;                   // numpy.load(path)[name]; the archive entry is name + ".npy"
    std::string descr;                  // dtype, see above: "<f4", "<i4", "<i8", "|u1", "<u2", "|S3" ...
    std::vector<std::uint64_t> shape;   // C order; {} is a scalar (one element)
    const void* data = nullptr;         // product(shape) elements, host byte order
    std::size_t bytes = 0;              // must equal product(shape) * itemsize
    // Instead of `data` (when set): gives the array's `bytes` bytes exactly as the file holds them
    // (in the descr's byte order), piece by piece as libzip pulls them (in order, a few KiB at a
    // time); for data converted or generated on the fly without a copy in memory. Fewer bytes in
    // all than `bytes` fail the write; so does an exception it throws, with the array named in
    // the message.
    NpyFill fill;
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
// as libzip pulls them (no converted copy is ever held): e.g. int64 indices stored as int32.
// Integer values that do not survive the conversion exactly fail the write (naming the array, the
// value and its index); a conversion to float rounds as static_cast does. Views `values` like
// npy_array.
template <class Out, class In>
NpyArray npy_converted(std::string name, const std::vector<In>& values, std::vector<std::uint64_t> shape) {
    const In* v = values.data();
    const std::size_t n = values.size();
    const std::string descr = npy_descr<Out>();
    auto fill = [v, n, descr](std::uint64_t offset, void* out, std::size_t len) -> std::size_t {
        constexpr std::size_t S = sizeof(Out);
        const std::uint64_t total = static_cast<std::uint64_t>(n) * S;
        if (offset >= total) return 0;
        len = static_cast<std::size_t>(std::min<std::uint64_t>(len, total - offset));
        auto* o = static_cast<unsigned char*>(out);
        for (std::size_t done = 0; done < len;) {
            const std::uint64_t at = offset + done;
            const std::size_t i = static_cast<std::size_t>(at / S), skip = static_cast<std::size_t>(at % S);
            const In x = v[i];
            const Out y = static_cast<Out>(x);
            if constexpr (std::is_integral_v<Out>) {
                if (static_cast<In>(y) != x || detail::negative(x) != detail::negative(y))
                    throw std::range_error("value " + std::to_string(x) + " at index " + std::to_string(i) +
                                           " does not fit '" + descr + "'");
            }
            unsigned char raw[S], le[S];
            std::memcpy(raw, &y, S);
            for (std::size_t b = 0; b < S; ++b) le[b] = detail::kHostLittle ? raw[b] : raw[S - 1 - b];
            const std::size_t m = std::min(S - skip, len - done);
            std::memcpy(o + done, le + skip, m);
            done += m;
        }
        return len;
    };
    NpyArray a{std::move(name), descr, std::move(shape), nullptr, n * sizeof(Out), {}};
    a.fill = std::move(fill);
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
