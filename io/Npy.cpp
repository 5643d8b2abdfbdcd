#include "io/Npy.h"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

namespace ltm::io {

namespace {

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
constexpr bool kHostLittle = true;
#else
constexpr bool kHostLittle = false;
#endif

constexpr std::size_t kMaxHeader = std::size_t(1) << 24;

[[noreturn]] void bad(const std::string& why) { throw NpyError(why); }

std::size_t get_le(const unsigned char* p, int n) {
    std::size_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}

// The header dict, one token at a time.
class DictParser {
public:
    explicit DictParser(std::string_view text) : s_(text) {}

    void parse(NpyHeader& h) {
        bool have_descr = false, have_order = false, have_shape = false;
        ws();
        expect('{');
        for (;;) {
            ws();
            if (peek() == '}') break;
            const std::string key = string();
            ws();
            expect(':');
            ws();
            if (key == "descr") {
                if (peek() == '[') fail("structured dtypes are not supported");
                h.descr = string();
                have_descr = true;
            } else if (key == "fortran_order") {
                h.fortran_order = word();
                have_order = true;
            } else if (key == "shape") {
                h.shape = tuple();
                have_shape = true;
            } else {
                fail("unexpected key '" + key + "'");
            }
            ws();
            if (peek() == ',') {
                ++i_;
                continue;
            }
            if (peek() != '}') fail("expected ',' or '}'");
        }
        if (!have_descr || !have_order || !have_shape) fail("the header lacks 'descr', 'fortran_order' or 'shape'");
    }

private:
    [[noreturn]] void fail(const std::string& why) const {
        bad("bad .npy header (" + why + "): " + std::string(s_.substr(0, 200)));
    }
    char peek() const { return i_ < s_.size() ? s_[i_] : '\0'; }
    void ws() {
        while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
    }
    void expect(char c) {
        if (peek() != c) fail(std::string("expected '") + c + "'");
        ++i_;
    }
    std::string string() {
        const char q = peek();
        if (q != '\'' && q != '"') fail("expected a string");
        const std::size_t b = ++i_;
        while (i_ < s_.size() && s_[i_] != q) ++i_;
        if (i_ >= s_.size()) fail("unterminated string");
        return std::string(s_.substr(b, i_++ - b));
    }
    bool word() {
        const std::size_t b = i_;
        while (i_ < s_.size() && std::isalpha(static_cast<unsigned char>(s_[i_]))) ++i_;
        const std::string_view w = s_.substr(b, i_ - b);
        if (w != "True" && w != "False") fail("expected True or False");
        return w == "True";
    }
    std::vector<std::uint64_t> tuple() {
        std::vector<std::uint64_t> v;
        expect('(');
        for (;;) {
            ws();
            if (peek() == ')') break;
            if (!std::isdigit(static_cast<unsigned char>(peek()))) fail("expected a non-negative integer in the shape");
            std::uint64_t x = 0;
            while (std::isdigit(static_cast<unsigned char>(peek()))) {
                if (x > (static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()) - 9) / 10)
                    fail("shape entry too large");
                x = x * 10 + static_cast<std::uint64_t>(s_[i_++] - '0');
            }
            if (peek() == 'L') ++i_;  // Python 2 long literal
            v.push_back(x);
            ws();
            if (peek() == ',') {
                ++i_;
                continue;
            }
            if (peek() != ')') fail("expected ',' or ')' in the shape");
        }
        ++i_;
        return v;
    }

    std::string_view s_;
    std::size_t i_ = 0;
};

void parse_descr(NpyHeader& h) {
    const std::string& d = h.descr;
    const auto fail = [&] { bad("unsupported dtype '" + d + "'"); };
    if (d.size() < 3) fail();
    const char order = d[0];
    if (order != '<' && order != '>' && order != '|' && order != '=') fail();
    if (!std::isalpha(static_cast<unsigned char>(d[1]))) fail();
    h.big_endian = order == '>' || (order == '=' && !kHostLittle);
    h.kind = d[1];
    std::size_t n = 0;
    for (std::size_t i = 2; i < d.size(); ++i) {
        if (!std::isdigit(static_cast<unsigned char>(d[i])) || n > 1000000) fail();
        n = n * 10 + static_cast<std::size_t>(d[i] - '0');
    }
    if (n == 0) fail();
    h.itemsize = h.kind == 'U' ? 4 * n : n;
}

}  // namespace

std::string npy_shape_repr(const std::vector<std::uint64_t>& shape) {
    if (shape.size() == 1) return "(" + std::to_string(shape[0]) + ",)";
    std::string s = "(";
    for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
    return s + ")";
}

std::string npy_preamble(const std::string& descr, const std::vector<std::uint64_t>& shape) {
    std::string dict = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + npy_shape_repr(shape) + ", }";
    const std::size_t unpadded = 10 + dict.size() + 1;  // magic 6, version 2, length 2, '\n'
    dict.append((64 - unpadded % 64) % 64, ' ');
    dict.push_back('\n');
    if (dict.size() > 0xFFFF) bad("the .npy header is too long (too many dimensions)");
    std::string out("\x93NUMPY\x01\x00", 8);
    out.push_back(static_cast<char>(dict.size() & 0xFF));
    out.push_back(static_cast<char>(dict.size() >> 8));
    return out + dict;
}

std::size_t npy_preamble_size(std::string_view head) {
    if (head.size() < 8) return 8;
    const auto* u = reinterpret_cast<const unsigned char*>(head.data());
    if (std::memcmp(u, "\x93NUMPY", 6) != 0) bad("not a .npy array (bad magic)");
    if ((u[6] != 1 && u[6] != 2 && u[6] != 3) || u[7] != 0)
        bad("unsupported .npy version " + std::to_string(u[6]) + "." + std::to_string(u[7]));
    const std::size_t prefix = u[6] == 1 ? 10 : 12;
    if (head.size() < prefix) return prefix;
    const std::size_t len = get_le(u + 8, u[6] == 1 ? 2 : 4);
    if (len == 0 || len > kMaxHeader) bad("implausible .npy header length " + std::to_string(len));
    return prefix + len;
}

NpyHeader parse_npy_preamble(std::string_view preamble) {
    NpyHeader h;
    h.preamble_size = npy_preamble_size(preamble);
    if (h.preamble_size != preamble.size())
        bad("the .npy preamble given is " + std::to_string(preamble.size()) + " bytes, its header says " +
            std::to_string(h.preamble_size));
    h.major = static_cast<unsigned char>(preamble[6]);
    h.minor = static_cast<unsigned char>(preamble[7]);
    const std::size_t prefix = h.major == 1 ? 10 : 12;
    DictParser(preamble.substr(prefix)).parse(h);
    parse_descr(h);
    for (std::uint64_t s : h.shape) {
        if (s != 0 && h.count > std::numeric_limits<std::uint64_t>::max() / s) bad("implausible shape");
        h.count *= s;
    }
    return h;
}

std::uint64_t npy_load_uint(const std::uint8_t* p, std::size_t size, bool big_endian) {
    std::uint64_t v = 0;
    for (std::size_t b = 0; b < size; ++b) {
        const std::uint8_t byte = big_endian ? p[b] : p[size - 1 - b];
        v = (v << 8) | byte;
    }
    return v;
}

double npy_load_float(const std::uint8_t* p, std::size_t size, bool big_endian) {
    const std::uint64_t u = npy_load_uint(p, size, big_endian);
    if (size == 4) {
        const auto u32 = static_cast<std::uint32_t>(u);
        float f;
        std::memcpy(&f, &u32, 4);
        return f;
    }
    double d;
    std::memcpy(&d, &u, 8);
    return d;
}

bool is_npy_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char magic[6] = {};
    return in.read(magic, 6) && std::memcmp(magic, "\x93NUMPY", 6) == 0;
}

NpyFloatArray read_npy_floats(const std::string& path) {
    auto fail = [&](const std::string& why) -> void { throw std::runtime_error("cannot read npy file '" + path + "': " + why); };
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(std::strerror(errno));
    // One read of the whole file (a 64-pattern stack of a 500 x 500 display is 64 MB; a stream
    // iterator took most of a second for it).
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    in.seekg(0, std::ios::beg);
    if (size < 0) fail("cannot tell its size");
    std::string bytes(static_cast<std::size_t>(size), '\0');
    if (!in.read(bytes.data(), size)) fail("read error");
    NpyHeader h;
    try {
        // The preamble's size in steps (npy_preamble_size): until it no longer changes.
        std::size_t want = 0;
        for (std::size_t next; (next = npy_preamble_size(std::string_view(bytes).substr(0, want))) != want; want = next)
            if (next > bytes.size()) fail("truncated .npy header (the file has " + std::to_string(bytes.size()) + " bytes)");
        h = parse_npy_preamble(std::string_view(bytes).substr(0, want));
    } catch (const NpyError& e) {
        fail(e.what());
    }
    if (h.kind != 'f' || (h.itemsize != 4 && h.itemsize != 8))
        fail("dtype '" + h.descr + "' is not float32 or float64");
    const std::uint64_t payload = bytes.size() - h.preamble_size;
    if (h.count > payload / h.itemsize || h.count * h.itemsize != payload)
        fail("its shape " + npy_shape_repr(h.shape) + " needs " + std::to_string(h.count) + " elements of " +
             std::to_string(h.itemsize) + " bytes, but it holds " + std::to_string(payload) + " bytes of data");
    NpyFloatArray a;
    a.shape = h.shape;
    a.values.resize(static_cast<std::size_t>(h.count));
    const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data()) + h.preamble_size;
    // C-order element c sits at file element f: f = c in C order; in Fortran order the first index
    // varies fastest, f = i0 + d0 (i1 + d1 (i2 + ...)), walked with an odometer over the C index.
    const std::size_t n = h.shape.size();
    std::vector<std::uint64_t> idx(n, 0), stride(n, 1);
    for (std::size_t d = 1; d < n; ++d) stride[d] = stride[d - 1] * h.shape[d - 1];
    if (!h.fortran_order && h.itemsize == 4 && h.big_endian != kHostLittle) {  // as it sits in memory
        if (h.count > 0) std::memcpy(a.values.data(), data, static_cast<std::size_t>(h.count) * 4);
        return a;
    }
    std::uint64_t f = 0;
    for (std::uint64_t c = 0; c < h.count; ++c) {
        const std::uint64_t at = h.fortran_order ? f : c;
        a.values[static_cast<std::size_t>(c)] =
            static_cast<float>(npy_load_float(data + at * h.itemsize, h.itemsize, h.big_endian));
        if (h.fortran_order)
            for (std::size_t d = n; d-- > 0;) {  // C order: the last index is incremented first
                f += stride[d];
                if (++idx[d] < h.shape[d]) break;
                f -= stride[d] * h.shape[d];
                idx[d] = 0;
            }
    }
    return a;
}

}  // namespace ltm::io
