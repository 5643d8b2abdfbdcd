#include "io/LtmFile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <new>
#include <stdexcept>
#include <vector>

#include "io/Npz.h"

namespace ltm {

// ---------------------------------------------------------------------------------------------
// Writing: the five arrays of scipy.sparse.save_npz, through io/Npz.h
// ---------------------------------------------------------------------------------------------

void write_ltm_npz(const std::string& path, const CsrMatrix& T, const NpzWriteOptions& options) {
    const std::string invalid = T.check();
    if (!invalid.empty()) throw std::runtime_error("cannot write LTM file '" + path + "': the matrix is invalid: " + invalid);
    try {
        // scipy's rule: int32 indptr unless nnz needs int64 (converted while writing, no copy).
        static const std::string csr = "csr";
        const std::vector<std::int64_t> shape = {T.rows, T.cols};
        io::write_npz(path,
                      {io::npy_array("indices", T.indices),
                       T.nnz() < (std::size_t(1) << 31) ? io::npy_converted<std::int32_t>("indptr", T.indptr)
                                                        : io::npy_array("indptr", T.indptr),
                       io::npy_bytes_scalar("format", csr), io::npy_array("shape", shape),
                       io::npy_array("data", T.data)},
                      options, "LTM file");
    } catch (const std::bad_alloc&) {
        throw std::runtime_error("cannot write LTM file '" + path + "': out of memory");
    }
}

// ---------------------------------------------------------------------------------------------
// Reading: a ZIP reader and .npy parser for what scipy and numpy write
// ---------------------------------------------------------------------------------------------

namespace {

constexpr std::uint32_t kSigLocal = 0x04034b50, kSigCentral = 0x02014b50, kSigEnd = 0x06054b50,
                        kSigEnd64 = 0x06064b50, kSigLocator64 = 0x07064b50;
constexpr std::uint64_t k32 = 0xFFFFFFFFull;  // a 32-bit field with this value defers to ZIP64
constexpr std::size_t kChunk = std::size_t(1) << 20;

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
constexpr bool kHostLittle = true;
#else
constexpr bool kHostLittle = false;
#endif

std::string errno_text(int e) { return std::strerror(e); }

std::uint16_t get16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
std::uint32_t get32(const std::uint8_t* p) {
    return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
           (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
std::uint64_t get64(const std::uint8_t* p) {
    return static_cast<std::uint64_t>(get32(p)) | (static_cast<std::uint64_t>(get32(p + 4)) << 32);
}


struct ReadError : std::runtime_error {
    using std::runtime_error::runtime_error;
};
[[noreturn]] void bad(const std::string& what) { throw ReadError(what); }

std::string hex32(std::uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%08x", v);
    return b;
}

class InFile {
public:
    explicit InFile(const std::string& path) {
        fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd_ < 0) {
            const int e = errno;
            if (e == ENOENT) bad("no such file");
            bad("cannot open it: " + errno_text(e));
        }
        struct stat st {};
        if (::fstat(fd_, &st) != 0) bad("cannot stat it: " + errno_text(errno));
        if (S_ISDIR(st.st_mode)) bad("it is a folder");
        if (!S_ISREG(st.st_mode)) bad("it is not a regular file");
        size_ = static_cast<std::uint64_t>(st.st_size);
    }
    ~InFile() {
        if (fd_ >= 0) ::close(fd_);
    }
    InFile(const InFile&) = delete;
    InFile& operator=(const InFile&) = delete;
    std::uint64_t size() const { return size_; }
    void read_at(std::uint64_t offset, void* buf, std::size_t n, const std::string& what) const {
        if (offset > size_ || n > size_ - offset)
            bad("truncated or corrupt archive: " + what + " (bytes " + std::to_string(offset) + ".." +
                std::to_string(offset + n) + ") extends past the end of the file (" + std::to_string(size_) +
                " bytes)");
        auto* p = static_cast<char*>(buf);
        while (n > 0) {
            const ssize_t r = ::pread(fd_, p, std::min<std::size_t>(n, std::size_t(1) << 30), static_cast<off_t>(offset));
            if (r < 0) {
                if (errno == EINTR) continue;
                bad("reading " + what + " failed: " + errno_text(errno));
            }
            if (r == 0) bad("unexpected end of file while reading " + what);
            p += r;
            n -= static_cast<std::size_t>(r);
            offset += static_cast<std::uint64_t>(r);
        }
    }

private:
    int fd_ = -1;
    std::uint64_t size_ = 0;
};

struct CdEntry {
    std::string name;
    std::uint16_t flags = 0, method = 0;
    std::uint32_t crc = 0;
    std::uint64_t csize = 0, usize = 0, offset = 0;
};

std::vector<CdEntry> read_central_directory(const InFile& f) {
    const std::uint64_t size = f.size();
    if (size == 0) bad("the file is empty");
    std::uint8_t head[8] = {};
    f.read_at(0, head, static_cast<std::size_t>(std::min<std::uint64_t>(size, 8)), "the first bytes");
    const bool starts_zip = size >= 4 && get32(head) == kSigLocal;
    if (size >= 6 && std::memcmp(head, "\x93NUMPY", 6) == 0)
        bad("it is a single .npy array, not an .npz archive (a ZIP of .npy arrays)");
    if (size < 22) bad(starts_zip ? "truncated ZIP archive (" + std::to_string(size) + " bytes)"
                                  : "not a ZIP archive (only " + std::to_string(size) + " bytes)");

    const std::size_t tail_n = static_cast<std::size_t>(std::min<std::uint64_t>(size, 22 + 65535));
    std::vector<std::uint8_t> tail(tail_n);
    f.read_at(size - tail_n, tail.data(), tail_n, "the end of the archive");
    std::ptrdiff_t found = -1;
    for (std::ptrdiff_t i = static_cast<std::ptrdiff_t>(tail_n) - 22; i >= 0; --i) {
        if (get32(&tail[static_cast<std::size_t>(i)]) == kSigEnd &&
            static_cast<std::size_t>(i) + 22 + get16(&tail[static_cast<std::size_t>(i) + 20]) <= tail_n) {
            found = i;
            break;
        }
    }
    if (found < 0)
        bad(starts_zip ? "truncated or corrupt ZIP archive (no end-of-central-directory record)"
                       : "not a ZIP archive (no end-of-central-directory record)");
    const std::uint8_t* eocd = &tail[static_cast<std::size_t>(found)];
    const std::uint64_t eocd_pos = size - tail_n + static_cast<std::uint64_t>(found);
    std::uint64_t disk = get16(eocd + 4), cd_disk = get16(eocd + 6), n = get16(eocd + 10),
                  cd_size = get32(eocd + 12), cd_offset = get32(eocd + 16);
    std::uint64_t cd_end_limit = eocd_pos;
    if (eocd_pos >= 20) {
        std::uint8_t loc[20];
        f.read_at(eocd_pos - 20, loc, 20, "the ZIP64 locator");
        if (get32(loc) == kSigLocator64) {
            const std::uint64_t rec_pos = get64(loc + 8);
            if (get32(loc + 16) > 1) bad("multi-disk ZIP archives are not supported");
            std::uint8_t rec[56];
            f.read_at(rec_pos, rec, 56, "the ZIP64 end-of-central-directory record");
            if (get32(rec) != kSigEnd64) bad("corrupt ZIP archive: bad ZIP64 end-of-central-directory record");
            disk = get32(rec + 16);
            cd_disk = get32(rec + 20);
            n = get64(rec + 32);
            cd_size = get64(rec + 40);
            cd_offset = get64(rec + 48);
            cd_end_limit = rec_pos;
        }
    }
    // Without a ZIP64 record the 16/32-bit values are taken literally, as Python does.
    if (disk != 0 || cd_disk != 0) bad("multi-disk ZIP archives are not supported");
    if (cd_offset > cd_end_limit || cd_size > cd_end_limit - cd_offset)
        bad("truncated or corrupt ZIP archive: the central directory (" + std::to_string(cd_size) + " bytes at " +
            std::to_string(cd_offset) + ") does not lie before its end record");
    if (n > cd_size / 46) bad("corrupt ZIP archive: " + std::to_string(n) + " entries cannot fit the central directory");

    std::vector<std::uint8_t> cd(static_cast<std::size_t>(cd_size));
    f.read_at(cd_offset, cd.data(), cd.size(), "the central directory");
    std::vector<CdEntry> entries;
    std::size_t pos = 0;
    for (std::uint64_t k = 0; k < n; ++k) {
        if (pos + 46 > cd.size() || get32(&cd[pos]) != kSigCentral)
            bad("corrupt ZIP archive: bad central directory entry " + std::to_string(k));
        const std::uint8_t* h = &cd[pos];
        CdEntry e;
        e.flags = get16(h + 8);
        e.method = get16(h + 10);
        e.crc = get32(h + 16);
        e.csize = get32(h + 20);
        e.usize = get32(h + 24);
        const std::size_t nlen = get16(h + 28), xlen = get16(h + 30), clen = get16(h + 32);
        e.offset = get32(h + 42);
        if (pos + 46 + nlen + xlen + clen > cd.size())
            bad("corrupt ZIP archive: central directory entry " + std::to_string(k) + " overruns the directory");
        e.name.assign(reinterpret_cast<const char*>(h + 46), nlen);
        const std::uint8_t* x = h + 46 + nlen;
        for (std::size_t xp = 0; xp + 4 <= xlen;) {
            const std::uint16_t id = get16(x + xp), len = get16(x + xp + 2);
            if (xp + 4 + len > xlen) bad("corrupt ZIP archive: bad extra field in entry '" + e.name + "'");
            if (id == 0x0001) {  // ZIP64: the deferred fields, in order
                std::size_t q = xp + 4;
                const std::size_t qend = xp + 4 + len;
                auto take = [&](std::uint64_t& field) {
                    if (q + 8 > qend) bad("corrupt ZIP archive: short ZIP64 field in entry '" + e.name + "'");
                    field = get64(x + q);
                    q += 8;
                };
                if (e.usize == k32) take(e.usize);
                if (e.csize == k32) take(e.csize);
                if (e.offset == k32) take(e.offset);
            }
            xp += 4 + len;
        }
        entries.push_back(e);
        pos += 46 + nlen + xlen + clen;
    }
    return entries;
}

struct Inflater {
    z_stream zs{};
    bool live = false;
    ~Inflater() {
        if (live) inflateEnd(&zs);
    }
};

// Streams the uncompressed bytes of an entry to `sink`, verifying its size and CRC-32.
void extract(const InFile& f, const CdEntry& e, const std::function<void(const std::uint8_t*, std::size_t)>& sink) {
    const std::string what = "entry '" + e.name + "'";
    if (e.flags & 0x0001) bad(what + " is encrypted");
    if (e.method != 0 && e.method != 8)
        bad(what + " uses compression method " + std::to_string(e.method) + " (only stored and deflate are supported)");
    std::uint8_t lh[30];
    f.read_at(e.offset, lh, 30, "the local header of " + what);
    if (get32(lh) != kSigLocal) bad("corrupt ZIP archive: bad local header of " + what);
    const std::size_t nlen = get16(lh + 26), xlen = get16(lh + 28);
    std::string lname(nlen, '\0');
    f.read_at(e.offset + 30, lname.data(), nlen, "the local header of " + what);
    if (lname != e.name)
        bad("corrupt ZIP archive: the local header of " + what + " names '" + lname + "'");
    const std::uint64_t data_pos = e.offset + 30 + nlen + xlen;
    if (data_pos > f.size() || e.csize > f.size() - data_pos)
        bad("truncated or corrupt archive: the data of " + what + " (" + std::to_string(e.csize) + " bytes at " +
            std::to_string(data_pos) + ") extends past the end of the file (" + std::to_string(f.size()) + " bytes)");
    if (e.method == 0 && e.csize != e.usize)
        bad("corrupt ZIP archive: stored " + what + " has compressed size " + std::to_string(e.csize) +
            " != size " + std::to_string(e.usize));
    if (e.method == 8 && e.usize > e.csize * 1032 + 1024)  // deflate expands at most 1032:1
        bad("corrupt ZIP archive: " + what + " claims " + std::to_string(e.usize) + " bytes from " +
            std::to_string(e.csize) + " compressed bytes");

    uLong crc = crc32(0L, Z_NULL, 0);
    std::uint64_t produced = 0;
    std::vector<std::uint8_t> in(kChunk);
    auto deliver = [&](const std::uint8_t* p, std::size_t n) {
        produced += n;
        if (produced > e.usize)
            bad("corrupt ZIP archive: " + what + " holds more than its recorded " + std::to_string(e.usize) + " bytes");
        crc = crc32_z(crc, p, n);
        sink(p, n);
    };
    if (e.method == 0) {
        for (std::uint64_t done = 0; done < e.csize;) {
            const std::size_t m = static_cast<std::size_t>(std::min<std::uint64_t>(in.size(), e.csize - done));
            f.read_at(data_pos + done, in.data(), m, "the data of " + what);
            deliver(in.data(), m);
            done += m;
        }
    } else {
        Inflater inf;
        if (inflateInit2(&inf.zs, -15) != Z_OK) bad("zlib's inflateInit2 failed");
        inf.live = true;
        std::vector<std::uint8_t> out(kChunk);
        std::uint64_t read = 0;
        int ret = Z_OK;
        while (ret != Z_STREAM_END) {
            if (inf.zs.avail_in == 0) {
                if (read == e.csize) bad("corrupt ZIP archive: the deflate stream of " + what + " ends early");
                const std::size_t m = static_cast<std::size_t>(std::min<std::uint64_t>(in.size(), e.csize - read));
                f.read_at(data_pos + read, in.data(), m, "the data of " + what);
                read += m;
                inf.zs.next_in = in.data();
                inf.zs.avail_in = static_cast<uInt>(m);
            }
            inf.zs.next_out = out.data();
            inf.zs.avail_out = static_cast<uInt>(out.size());
            ret = inflate(&inf.zs, Z_NO_FLUSH);
            if (ret == Z_DATA_ERROR || ret == Z_NEED_DICT || ret == Z_MEM_ERROR || ret == Z_STREAM_ERROR)
                bad("corrupt ZIP archive: bad deflate data in " + what + " (zlib: " +
                    (inf.zs.msg ? inf.zs.msg : std::to_string(ret)) + ")");
            const std::size_t have = out.size() - inf.zs.avail_out;
            if (have > 0) deliver(out.data(), have);
        }
    }
    if (produced != e.usize)
        bad("corrupt ZIP archive: " + what + " holds " + std::to_string(produced) + " bytes, its header says " +
            std::to_string(e.usize));
    if (static_cast<std::uint32_t>(crc) != e.crc)
        bad("CRC-32 mismatch in " + what + " (recorded " + hex32(e.crc) + ", computed " +
            hex32(static_cast<std::uint32_t>(crc)) + "): the file is corrupt");
}

// ----- .npy parsing -----

struct NpyInfo {
    std::string descr;
    bool big_endian = false;
    char kind = '?';
    std::size_t itemsize = 0;  // bytes per element
    std::vector<std::int64_t> shape;
    std::uint64_t count = 1;
};

class HeaderParser {
public:
    HeaderParser(const std::string& text, const std::string& entry) : s_(text), entry_(entry) {}

    NpyInfo parse() {
        NpyInfo info;
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
                info.descr = string();
                have_descr = true;
            } else if (key == "fortran_order") {
                word();
                have_order = true;
            } else if (key == "shape") {
                info.shape = tuple();
                have_shape = true;
            } else {
                fail("unexpected key '" + key + "'");
            }
            ws();
            if (peek() == ',') {
                ++i_;
                continue;
            }
            ws();
            if (peek() != '}') fail("expected ',' or '}'");
        }
        if (!have_descr || !have_order || !have_shape) fail("the header lacks 'descr', 'fortran_order' or 'shape'");
        return info;
    }

private:
    [[noreturn]] void fail(const std::string& why) {
        bad("corrupt array " + entry_ + ": bad .npy header (" + why + "): " + s_.substr(0, 200));
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
        ++i_;
        const std::size_t b = i_;
        while (i_ < s_.size() && s_[i_] != q) ++i_;
        if (i_ >= s_.size()) fail("unterminated string");
        return s_.substr(b, i_++ - b);
    }
    std::string word() {
        const std::size_t b = i_;
        while (i_ < s_.size() && std::isalpha(static_cast<unsigned char>(s_[i_]))) ++i_;
        const std::string w = s_.substr(b, i_ - b);
        if (w != "True" && w != "False") fail("expected True or False");
        return w;
    }
    std::vector<std::int64_t> tuple() {
        std::vector<std::int64_t> v;
        expect('(');
        for (;;) {
            ws();
            if (peek() == ')') break;
            if (!std::isdigit(static_cast<unsigned char>(peek()))) fail("expected a non-negative integer in the shape");
            std::int64_t x = 0;
            while (std::isdigit(static_cast<unsigned char>(peek()))) {
                if (x > (std::numeric_limits<std::int64_t>::max() - 9) / 10) fail("shape entry too large");
                x = x * 10 + (s_[i_++] - '0');
            }
            if (peek() == 'L') ++i_;  // Python 2 long literal
            v.push_back(x);
            ws();
            if (peek() == ',') {
                ++i_;
                continue;
            }
            ws();
            if (peek() != ')') fail("expected ',' or ')' in the shape");
        }
        ++i_;
        return v;
    }

    std::string s_;
    std::string entry_;
    std::size_t i_ = 0;
};

void parse_descr(NpyInfo& info, const std::string& entry) {
    const std::string& d = info.descr;
    auto fail = [&] { bad("array " + entry + " has the unsupported dtype '" + d + "'"); };
    if (d.size() < 3) fail();
    const char order = d[0];
    if (order != '<' && order != '>' && order != '|' && order != '=') fail();
    info.big_endian = order == '>' || (order == '=' && !kHostLittle);
    info.kind = d[1];
    std::size_t n = 0;
    for (std::size_t i = 2; i < d.size(); ++i) {
        if (!std::isdigit(static_cast<unsigned char>(d[i])) || n > 1000000) fail();
        n = n * 10 + static_cast<std::size_t>(d[i] - '0');
    }
    if (n == 0) fail();
    info.itemsize = info.kind == 'U' ? 4 * n : n;
}

// Consumes the bytes of one .npy entry: the header, then whole elements passed to on_elements.
class NpyStream {
public:
    using OnHeader = std::function<void(NpyInfo&)>;
    using OnElements = std::function<void(const std::uint8_t*, std::size_t count)>;

    NpyStream(std::string entry, std::uint64_t entry_size, OnHeader on_header, OnElements on_elements)
        : entry_(std::move(entry)), entry_size_(entry_size), on_header_(std::move(on_header)),
          on_elements_(std::move(on_elements)) {}

    void feed(const std::uint8_t* p, std::size_t n) {
        while (!have_header_ && n > 0) {
            const std::size_t want = target();
            const std::size_t m = std::min(n, want - head_.size());
            head_.append(reinterpret_cast<const char*>(p), m);
            p += m;
            n -= m;
            if (head_.size() == want) advance();
        }
        if (n > 0) payload(p, n);
    }

    void finish() {
        if (!have_header_) bad("array " + entry_ + " is truncated (incomplete .npy header)");
        if (done_ != info_.count || !carry_.empty())
            bad("array " + entry_ + " is truncated (" + std::to_string(done_) + " of " + std::to_string(info_.count) +
                " elements)");
    }

private:
    // How many bytes of the preamble to gather next: the magic and version (8), then the header
    // length field (to byte 10 in version 1, 12 in versions 2 and 3), then the whole header.
    std::size_t target() const { return prefix_ == 0 ? 8 : header_total_ == 0 ? prefix_ : header_total_; }

    void advance() {
        const auto* u = reinterpret_cast<const std::uint8_t*>(head_.data());
        if (prefix_ == 0) {
            if (std::memcmp(u, "\x93NUMPY", 6) != 0) bad("array " + entry_ + " is not a .npy array (bad magic)");
            if (u[6] == 1)
                prefix_ = 10;
            else if (u[6] == 2 || u[6] == 3)
                prefix_ = 12;
            else
                bad("array " + entry_ + " has the unsupported .npy version " + std::to_string(u[6]) + "." +
                    std::to_string(u[7]));
        } else if (header_total_ == 0) {
            const std::size_t len = prefix_ == 10 ? get16(u + 8) : get32(u + 8);
            if (len == 0 || len > (std::size_t(1) << 24))
                bad("array " + entry_ + " has an implausible .npy header length " + std::to_string(len));
            header_total_ = prefix_ + len;
        } else {
            parse_header();
        }
    }

    void parse_header() {
        info_ = HeaderParser(head_.substr(prefix_), entry_).parse();
        parse_descr(info_, entry_);
        info_.count = 1;
        for (std::int64_t s : info_.shape) {
            if (s != 0 && info_.count > std::numeric_limits<std::uint64_t>::max() / static_cast<std::uint64_t>(s))
                bad("array " + entry_ + " has an implausible shape");
            info_.count *= static_cast<std::uint64_t>(s);
        }
        const std::uint64_t payload = entry_size_ - std::min<std::uint64_t>(entry_size_, header_total_);
        if (info_.count > payload / info_.itemsize || info_.count * info_.itemsize != payload)
            bad("array " + entry_ + " is corrupt: its header describes " + std::to_string(info_.count) +
                " elements of " + std::to_string(info_.itemsize) + " bytes, but it holds " + std::to_string(payload) +
                " bytes of data");
        have_header_ = true;
        on_header_(info_);
    }

    void payload(const std::uint8_t* p, std::size_t n) {
        const std::size_t is = info_.itemsize;
        if (!carry_.empty()) {
            const std::size_t m = std::min(n, is - carry_.size());
            carry_.insert(carry_.end(), p, p + m);
            p += m;
            n -= m;
            if (carry_.size() < is) return;
            emit(carry_.data(), 1);
            carry_.clear();
        }
        const std::size_t whole = n / is;
        if (whole > 0) emit(p, whole);
        carry_.assign(p + whole * is, p + n);
    }

    void emit(const std::uint8_t* p, std::size_t count) {
        if (done_ + count > info_.count) bad("array " + entry_ + " holds more elements than its shape says");
        on_elements_(p, count);
        done_ += count;
    }

    std::string entry_;
    std::uint64_t entry_size_;
    OnHeader on_header_;
    OnElements on_elements_;
    std::string head_;
    std::size_t prefix_ = 0, header_total_ = 0;
    bool have_header_ = false;
    NpyInfo info_;
    std::vector<std::uint8_t> carry_;
    std::uint64_t done_ = 0;
};

std::uint64_t load_uint(const std::uint8_t* p, std::size_t size, bool big) {
    std::uint64_t v = 0;
    for (std::size_t b = 0; b < size; ++b) {
        const std::uint8_t byte = big ? p[b] : p[size - 1 - b];
        v = (v << 8) | byte;
    }
    return v;
}
std::int64_t load_int(const std::uint8_t* p, std::size_t size, bool big) {
    const std::uint64_t u = load_uint(p, size, big);
    if (size == 8) return static_cast<std::int64_t>(u);
    const std::uint64_t sign = std::uint64_t(1) << (8 * size - 1);
    return static_cast<std::int64_t>((u ^ sign)) - static_cast<std::int64_t>(sign);
}
double load_float(const std::uint8_t* p, std::size_t size, bool big) {
    const std::uint64_t u = load_uint(p, size, big);
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

std::string list_names(const std::vector<CdEntry>& entries) {
    if (entries.empty()) return "no entries";
    std::string s;
    for (const CdEntry& e : entries) s += (s.empty() ? "" : ", ") + e.name;
    return s;
}

const CdEntry& find_entry(const std::vector<CdEntry>& entries, const std::string& name) {
    const CdEntry* found = nullptr;
    for (const CdEntry& e : entries) {
        if (e.name != name) continue;
        if (found) bad("corrupt archive: it holds two entries named '" + name + "'");
        found = &e;
    }
    if (!found)
        bad("missing array '" + name + "': not a scipy.sparse CSR matrix file (the archive holds " +
            list_names(entries) + ")");
    return *found;
}

// Reads one array entry; `on_header` validates dtype and shape (throwing), `on_elements` converts.
void read_array(const InFile& f, const CdEntry& e, const NpyStream::OnHeader& on_header,
                const NpyStream::OnElements& on_elements) {
    NpyStream npy("'" + e.name + "'", e.usize, on_header, on_elements);
    extract(f, e, [&](const std::uint8_t* p, std::size_t n) { npy.feed(p, n); });
    npy.finish();
}

void require_1d(const NpyInfo& info, const std::string& name) {
    if (info.shape.size() != 1)
        bad("bad shape of array '" + name + "': it has " + std::to_string(info.shape.size()) +
            " dimensions, expected 1");
}

CsrMatrix read_npz(const InFile& f) {
    const std::vector<CdEntry> entries = read_central_directory(f);
    CsrMatrix T;

    // format: a bytes or str scalar "csr"
    std::string format;
    {
        NpyInfo fi;
        read_array(
            f, find_entry(entries, "format.npy"),
            [&](NpyInfo& info) {
                if ((info.kind != 'S' && info.kind != 'U') || info.count != 1)
                    bad("array 'format.npy' should be a string scalar such as b'csr', but has dtype '" + info.descr +
                        "' and " + std::to_string(info.count) + " elements");
                fi = info;
            },
            [&](const std::uint8_t* p, std::size_t) {
                if (fi.kind == 'S') {
                    for (std::size_t i = 0; i < fi.itemsize; ++i)
                        if (p[i]) format.push_back(static_cast<char>(p[i]));
                } else {
                    for (std::size_t i = 0; i + 4 <= fi.itemsize; i += 4) {
                        const auto c = static_cast<std::uint32_t>(load_uint(p + i, 4, fi.big_endian));
                        if (c) format.push_back(c < 128 ? static_cast<char>(c) : '?');
                    }
                }
            });
    }
    if (format != "csr") bad("it holds a sparse matrix in format '" + format + "', not a CSR matrix");

    for (const char* name : {"shape.npy", "indptr.npy", "indices.npy", "data.npy"}) find_entry(entries, name);

    // shape: two non-negative integers
    std::vector<std::int64_t> shape;
    {
        NpyInfo si;
        read_array(
            f, find_entry(entries, "shape.npy"),
            [&](NpyInfo& info) {
                if ((info.kind != 'i' && info.kind != 'u') || (info.itemsize != 4 && info.itemsize != 8))
                    bad("bad dtype '" + info.descr + "' of array 'shape.npy' (expected int64 or int32)");
                if (info.shape != std::vector<std::int64_t>{2})
                    bad("bad shape of array 'shape.npy': expected (2,), a matrix shape");
                si = info;
            },
            [&](const std::uint8_t* p, std::size_t count) {
                for (std::size_t i = 0; i < count; ++i) {
                    const std::uint8_t* q = p + i * si.itemsize;
                    if (si.kind == 'u' && si.itemsize == 8 && load_uint(q, 8, si.big_endian) > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
                        bad("matrix shape entry too large in 'shape.npy'");
                    shape.push_back(si.kind == 'u' ? static_cast<std::int64_t>(load_uint(q, si.itemsize, si.big_endian))
                                                   : load_int(q, si.itemsize, si.big_endian));
                }
            });
        if (shape[0] < 0 || shape[1] < 0)
            bad("bad matrix shape (" + std::to_string(shape[0]) + ", " + std::to_string(shape[1]) + ") in 'shape.npy'");
        T.rows = shape[0];
        T.cols = shape[1];
    }

    // indptr: rows + 1 integers
    {
        NpyInfo ii;
        read_array(
            f, find_entry(entries, "indptr.npy"),
            [&](NpyInfo& info) {
                if (info.kind != 'i' || (info.itemsize != 4 && info.itemsize != 8))
                    bad("bad dtype '" + info.descr + "' of array 'indptr.npy' (expected int32 or int64)");
                require_1d(info, "indptr.npy");
                if (static_cast<std::uint64_t>(info.shape[0]) != static_cast<std::uint64_t>(T.rows) + 1)
                    bad("bad shape of array 'indptr.npy': " + std::to_string(info.shape[0]) +
                        " entries, expected rows + 1 = " + std::to_string(T.rows + 1));
                ii = info;
                T.indptr.reserve(static_cast<std::size_t>(info.count));
            },
            [&](const std::uint8_t* p, std::size_t count) {
                for (std::size_t i = 0; i < count; ++i)
                    T.indptr.push_back(load_int(p + i * ii.itemsize, ii.itemsize, ii.big_endian));
            });
    }

    // indices: int32, converted from int64 when they fit
    {
        NpyInfo ii;
        read_array(
            f, find_entry(entries, "indices.npy"),
            [&](NpyInfo& info) {
                if (info.kind != 'i' || (info.itemsize != 4 && info.itemsize != 8))
                    bad("bad dtype '" + info.descr + "' of array 'indices.npy' (expected int32 or int64)");
                require_1d(info, "indices.npy");
                ii = info;
                T.indices.reserve(static_cast<std::size_t>(info.count));
            },
            [&](const std::uint8_t* p, std::size_t count) {
                if (ii.itemsize == 4 && !ii.big_endian && kHostLittle) {
                    const std::size_t old = T.indices.size();
                    T.indices.resize(old + count);
                    std::memcpy(T.indices.data() + old, p, count * 4);
                    return;
                }
                for (std::size_t i = 0; i < count; ++i) {
                    const std::int64_t v = load_int(p + i * ii.itemsize, ii.itemsize, ii.big_endian);
                    if (v < std::numeric_limits<std::int32_t>::min() || v > std::numeric_limits<std::int32_t>::max())
                        bad("column index " + std::to_string(v) + " of nonzero " + std::to_string(T.indices.size()) +
                            " in 'indices.npy' does not fit int32");
                    T.indices.push_back(static_cast<std::int32_t>(v));
                }
            });
    }

    // data: float32, converted from float64
    {
        NpyInfo di;
        read_array(
            f, find_entry(entries, "data.npy"),
            [&](NpyInfo& info) {
                if (info.kind != 'f' || (info.itemsize != 4 && info.itemsize != 8))
                    bad("bad dtype '" + info.descr + "' of array 'data.npy' (expected float32 or float64)");
                require_1d(info, "data.npy");
                if (info.count != T.indices.size())
                    bad("bad shape of array 'data.npy': " + std::to_string(info.count) + " values but " +
                        std::to_string(T.indices.size()) + " column indices");
                di = info;
                T.data.reserve(static_cast<std::size_t>(info.count));
            },
            [&](const std::uint8_t* p, std::size_t count) {
                if (di.itemsize == 4 && !di.big_endian && kHostLittle) {
                    const std::size_t old = T.data.size();
                    T.data.resize(old + count);
                    std::memcpy(T.data.data() + old, p, count * 4);
                    return;
                }
                for (std::size_t i = 0; i < count; ++i) {
                    const double v = load_float(p + i * di.itemsize, di.itemsize, di.big_endian);
                    const auto fv = static_cast<float>(v);
                    if (std::isfinite(v) && !std::isfinite(fv))
                        bad("value " + std::to_string(v) + " of nonzero " + std::to_string(T.data.size()) +
                            " in 'data.npy' overflows float32");
                    T.data.push_back(fv);
                }
            });
    }

    const std::string invalid = T.check();
    if (!invalid.empty()) bad("not a valid CSR matrix: " + invalid);
    return T;
}

}  // namespace

CsrMatrix read_ltm_npz(const std::string& path) {
    try {
        InFile f(path);
        return read_npz(f);
    } catch (const ReadError& e) {
        throw std::runtime_error("cannot read LTM file '" + path + "': " + e.what());
    } catch (const std::bad_alloc&) {
        throw std::runtime_error("cannot read LTM file '" + path + "': out of memory");
    } catch (const std::length_error& e) {
        throw std::runtime_error("cannot read LTM file '" + path + "': implausible array size (" + e.what() + ")");
    }
}

}  // namespace ltm
