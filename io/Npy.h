#pragma once
// The NumPy .npy preamble (the bytes before an array's data), formatted for writing and parsed for
// reading; io/Npz.h and io/LtmFile.h use it. The ZIP archive around the arrays is libzip's.
//
// Layout (numpy's "format" module, versions 1.0, 2.0 and 3.0):
//   "\x93NUMPY", major and minor version bytes, the header length (little-endian: uint16 in
//   version 1.0, uint32 in 2.0 and 3.0), then the header: a Python dict literal
//     {'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }
//   padded with spaces and ended by '\n' (3.0 allows UTF-8 in it, 1.0 and 2.0 are Latin-1; the
//   keys we read are ASCII either way). The array's bytes follow in the order fortran_order says.
//
// Writing (npy_preamble): always version 1.0, C order (fortran_order False), keys in numpy's order,
// the shape as Python's repr of a tuple ("()", "(5,)", "(2, 3)"), padded so that the whole preamble
// is a multiple of 64 bytes, exactly as numpy.save pads it.
//
// Reading (npy_preamble_size, then parse_npy_preamble): versions 1.0, 2.0 and 3.0 (any minor
// version 0; other versions are refused); the dict's keys in any order, quoted with ' or ",
// whitespace anywhere between tokens, a trailing comma or none; it must have exactly the keys
// 'descr' (a dtype string, not a structured dtype list), 'fortran_order' (True or False) and
// 'shape' (a tuple of non-negative integers, Python 2's "L" suffix allowed). The descr is
// "<order><kind><n>": order '<' little, '>' big, '|' not applicable, '=' native; kind any letter
// ('U' has n 4-byte code units, so itemsize 4n; every other kind has itemsize n >= 1). What the
// caller makes of kind and itemsize is its own business (io/LtmFile.h accepts a few).
// Errors are NpyError with a reason that does not name the array (the caller adds it).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace ltm::io {

struct NpyError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Python's repr of a shape tuple: "()", "(N,)", "(A, B)", ...
std::string npy_shape_repr(const std::vector<std::uint64_t>& shape);

// The version-1.0 preamble of a C-order array of `descr` and `shape`, a multiple of 64 bytes long.
// Throws NpyError when the header does not fit version 1.0's 16-bit length (thousands of
// dimensions; numpy allows at most 64).
std::string npy_preamble(const std::string& descr, const std::vector<std::uint64_t>& shape);

struct NpyHeader {
    int major = 0, minor = 0;        // format version
    std::size_t preamble_size = 0;   // bytes before the array's data
    std::string descr;               // as written, e.g. "<f4"
    char kind = '?';                 // descr[1]: 'f', 'i', 'u', 'b', 'S', 'U', ...
    bool big_endian = false;         // '>' (or '=' on a big-endian host)
    std::size_t itemsize = 0;        // bytes per element
    bool fortran_order = false;
    std::vector<std::uint64_t> shape;
    std::uint64_t count = 1;         // product(shape); NpyError if it overflows 64 bits
};

// How far to read into a .npy before calling again: given the first bytes of it (`head`, possibly
// empty), the preamble's full size once `head` holds enough of it to tell (its first 10 bytes in
// version 1.0, 12 in 2.0 and 3.0), else the number of bytes to read before asking again (8, 10 or
// 12). So: read until head.size() equals the result and the result no longer changes. Throws
// NpyError on bad magic, an unsupported version, or a header length of 0 or above 16 MiB.
std::size_t npy_preamble_size(std::string_view head);

// Parses a complete preamble (npy_preamble_size(preamble) == preamble.size()). Throws NpyError.
NpyHeader parse_npy_preamble(std::string_view preamble);

// One element as a file holds it: an unsigned integer of `size` bytes (1..8), or an IEEE float of
// 4 or 8 bytes, big- or little-endian; the result converted exactly (a float32 widened to double).
std::uint64_t npy_load_uint(const std::uint8_t* p, std::size_t size, bool big_endian);
double npy_load_float(const std::uint8_t* p, std::size_t size, bool big_endian);

// True if the file at `path` starts with the .npy magic "\x93NUMPY" (false if it cannot be read):
// how a reader tells a .npy from an image, by its first bytes and never by the extension.
bool is_npy_file(const std::string& path);

// A whole .npy file of floating-point numbers, such as numpy.save writes for a user's data (a
// stack of display patterns): dtype float32 or float64 in either byte order ('<f4', '>f4', '<f8',
// '>f8'), C or Fortran order, any shape. `values` is in C order (the last index varies fastest;
// a Fortran-order file is reordered), float64 rounded to the nearest float (beyond float's range:
// +-inf; the caller checks finiteness where it matters). Throws std::runtime_error
// "cannot read npy file 'PATH': reason" for a missing or unreadable file, a bad preamble, another
// dtype, or data shorter or longer than the shape says.
struct NpyFloatArray {
    std::vector<std::uint64_t> shape;
    std::vector<float> values;
};
NpyFloatArray read_npy_floats(const std::string& path);

}  // namespace ltm::io
