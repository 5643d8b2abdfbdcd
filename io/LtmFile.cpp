#include "io/LtmFile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zip.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <new>
#include <random>
#include <stdexcept>
#include <vector>

#include "io/Npy.h"
#include "io/Npz.h"

namespace ltm {

// ---------------------------------------------------------------------------------------------
// Writing: the five arrays of scipy.sparse.save_npz, through io/Npz.h
// ---------------------------------------------------------------------------------------------

namespace {

// The five arrays of write_ltm_npz, in scipy's order, with indices and data as given (viewed from
// memory or filled from spill files): the one place that says what an ltm.npz holds, so the
// in-memory and the streamed file cannot differ.
void write_csr_arrays(const std::string& path, std::int64_t rows, std::int64_t cols, std::size_t nnz,
                      const std::vector<std::int64_t>& indptr, io::NpyArray indices, io::NpyArray data,
                      const NpzWriteOptions& options) {
    try {
        // scipy's rule: int32 indptr unless nnz needs int64 (converted while writing, no copy).
        static const std::string csr = "csr";
        const std::vector<std::int64_t> shape = {rows, cols};
        io::write_npz(path,
                      {std::move(indices),
                       nnz < (std::size_t(1) << 31) ? io::npy_converted<std::int32_t>("indptr", indptr)
                                                    : io::npy_array("indptr", indptr),
                       io::npy_bytes_scalar("format", csr), io::npy_array("shape", shape), std::move(data)},
                      options, "LTM file");
    } catch (const std::bad_alloc&) {
        throw std::runtime_error("cannot write LTM file '" + path + "': out of memory");
    }
}

}  // namespace

void write_ltm_npz(const std::string& path, const CsrMatrix& T, const NpzWriteOptions& options) {
    const std::string invalid = T.check();
    if (!invalid.empty()) throw std::runtime_error("cannot write LTM file '" + path + "': the matrix is invalid: " + invalid);
    write_csr_arrays(path, T.rows, T.cols, T.nnz(), T.indptr, io::npy_array("indices", T.indices),
                     io::npy_array("data", T.data), options);
}

// ---------------------------------------------------------------------------------------------
// Streaming: spill files beside the target, read back while libzip pulls the entries
// ---------------------------------------------------------------------------------------------

namespace {

// An unnamed file in `folder` (see LtmFileStream); -1 with errno set on failure.
int open_spill_file(const std::string& folder, const std::string& name) {
    int fd = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd >= 0) return fd;
    if (errno != EOPNOTSUPP && errno != EISDIR && errno != EINVAL) return -1;
    // No O_TMPFILE here: a named file, unlinked as soon as it exists.
    std::random_device rd;
    for (int attempt = 0; attempt < 16; ++attempt) {
        char hex[17];
        std::snprintf(hex, sizeof hex, "%08x%08x", rd(), rd());
        const std::string p = folder + "/." + name + ".spill-" + hex;
        fd = ::open(p.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
        if (fd >= 0) {
            ::unlink(p.c_str());
            return fd;
        }
        if (errno != EEXIST) return -1;
    }
    return -1;
}

void write_all(int fd, const void* bytes, std::size_t n, std::uint64_t at) {
    const auto* p = static_cast<const unsigned char*>(bytes);
    while (n > 0) {
        const ssize_t w = ::pwrite(fd, p, n, static_cast<off_t>(at));
        if (w < 0) {
            if (errno == EINTR) continue;
            throw std::runtime_error(std::string("writing a spill file failed: ") + std::strerror(errno));
        }
        p += w;
        at += static_cast<std::uint64_t>(w);
        n -= static_cast<std::size_t>(w);
    }
}

// A 1-D array of `count` 4-byte little-endian elements (the host's order on the little-endian
// machines ltmsim runs on; checked below) read from a spill file as libzip pulls it.
io::NpyArray spilled_array(const std::string& name, const char* descr, int fd, std::size_t count) {
    io::NpyArray a{name, descr, {static_cast<std::uint64_t>(count)}, nullptr, count * 4, {}};
    a.fill = [fd, total = count * 4](std::uint64_t offset, void* out, std::size_t n) -> std::size_t {
        if (offset >= total) return 0;
        n = static_cast<std::size_t>(std::min<std::uint64_t>(n, total - offset));
        auto* o = static_cast<unsigned char*>(out);
        std::size_t done = 0;
        while (done < n) {
            const ssize_t r = ::pread(fd, o + done, n - done, static_cast<off_t>(offset + done));
            if (r < 0 && errno == EINTR) continue;
            if (r < 0) throw std::runtime_error(std::string("reading its spill file failed: ") + std::strerror(errno));
            if (r == 0) throw std::runtime_error("its spill file ended early");
            done += static_cast<std::size_t>(r);
        }
        return n;
    };
    return a;
}

}  // namespace

LtmFileStream::LtmFileStream(const std::string& path, std::int64_t rows, std::int64_t cols, const NpzWriteOptions& options)
    : path_(path), rows_(rows), cols_(cols), options_(options) {
    static_assert(sizeof(float) == 4 && sizeof(std::int32_t) == 4, "4-byte indices and values");
    if (!io::detail::kHostLittle) fail("streaming needs a little-endian host (the spill files hold the host's bytes)");
    if (rows < 0 || cols < 0) fail("negative shape");
    const std::size_t slash = path.find_last_of('/');
    const std::string folder = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
    const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
    indices_fd_ = open_spill_file(folder, name);
    if (indices_fd_ < 0) fail("cannot create a spill file in folder '" + folder + "': " + std::strerror(errno));
    data_fd_ = open_spill_file(folder, name);
    if (data_fd_ < 0) {
        const int e = errno;
        ::close(indices_fd_);
        indices_fd_ = -1;
        fail("cannot create a spill file in folder '" + folder + "': " + std::strerror(e));
    }
    indptr_.reserve(static_cast<std::size_t>(rows) + 1);
}

LtmFileStream::~LtmFileStream() {
    if (indices_fd_ >= 0) ::close(indices_fd_);
    if (data_fd_ >= 0) ::close(data_fd_);
}

void LtmFileStream::fail(const std::string& why) const {
    throw std::runtime_error("cannot write LTM file '" + path_ + "': " + why);
}

void LtmFileStream::append(const CsrMatrix& block) {
    if (indices_fd_ < 0) fail("the stream is already committed");
    if (block.cols != cols_)
        fail("a block of " + std::to_string(block.cols) + " columns for a matrix of " + std::to_string(cols_));
    if (rows_written() + block.rows > rows_)
        fail("rows " + std::to_string(rows_written()) + " + " + std::to_string(block.rows) + " exceed the matrix's " +
             std::to_string(rows_));
    const std::string invalid = block.check();
    if (!invalid.empty()) fail("the block at row " + std::to_string(rows_written()) + " is invalid: " + invalid);
    const std::uint64_t at = static_cast<std::uint64_t>(nnz()) * 4;
    try {
        write_all(indices_fd_, block.indices.data(), block.indices.size() * 4, at);
        write_all(data_fd_, block.data.data(), block.data.size() * 4, at);
    } catch (const std::runtime_error& e) {
        fail(e.what());
    }
    const std::int64_t base = indptr_.back();
    for (std::int64_t r = 1; r <= block.rows; ++r) indptr_.push_back(base + block.indptr[static_cast<std::size_t>(r)]);
}

void LtmFileStream::commit(io::CommitGroup* group) {
    if (indices_fd_ < 0) fail("the stream is already committed");
    if (rows_written() != rows_)
        fail("only " + std::to_string(rows_written()) + " of " + std::to_string(rows_) + " rows were given");
    const std::size_t n = nnz();
    NpzWriteOptions options = options_;
    if (group) options.group = group;
    write_csr_arrays(path_, rows_, cols_, n, indptr_, spilled_array("indices", "<i4", indices_fd_, n),
                     spilled_array("data", "<f4", data_fd_, n), options);
    ::close(indices_fd_);
    ::close(data_fd_);
    indices_fd_ = data_fd_ = -1;
}

// ---------------------------------------------------------------------------------------------
// Reading: libzip opens the archive and inflates the entries (checking sizes and CRC-32s); each
// entry is parsed as a .npy stream (io/Npy.h) and converted as it arrives
// ---------------------------------------------------------------------------------------------

namespace {

constexpr std::size_t kChunk = std::size_t(1) << 20;

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
constexpr bool kHostLittle = true;
#else
constexpr bool kHostLittle = false;
#endif

struct ReadError : std::runtime_error {
    using std::runtime_error::runtime_error;
};
[[noreturn]] void bad(const std::string& what) { throw ReadError(what); }

std::string hex32(std::uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%08x", v);
    return b;
}

std::string libzip_text(const zip_error_t* e) {
    return std::string("libzip: ") + zip_error_strerror(const_cast<zip_error_t*>(e));
}
std::string libzip_text(int code) {
    zip_error_t e;
    zip_error_init_with_code(&e, code);
    std::string s = libzip_text(&e);
    zip_error_fini(&e);
    return s;
}

// What the file is, before libzip looks at it: the errors of a path that is no ZIP at all.
// Returns whether it begins like a ZIP archive (a local file header).
bool inspect_file(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        const int e = errno;
        if (e == ENOENT) bad("no such file");
        bad(std::string("cannot open it: ") + std::strerror(e));
    }
    struct stat st {};
    const int r = ::fstat(fd, &st);
    const int e = errno;
    unsigned char head[8] = {};
    const ssize_t n = r == 0 && S_ISREG(st.st_mode) ? ::pread(fd, head, sizeof head, 0) : 0;
    ::close(fd);
    if (r != 0) bad(std::string("cannot stat it: ") + std::strerror(e));
    if (S_ISDIR(st.st_mode)) bad("it is a folder");
    if (!S_ISREG(st.st_mode)) bad("it is not a regular file");
    if (st.st_size == 0) bad("the file is empty");
    if (n >= 6 && std::memcmp(head, "\x93NUMPY", 6) == 0)
        bad("it is a single .npy array, not an .npz archive (a ZIP of .npy arrays)");
    return n >= 4 && std::memcmp(head, "PK\x03\x04", 4) == 0;
}

// The archive, open in libzip (read-only; its names listed once).
class Archive {
public:
    explicit Archive(const std::string& path) {
        const bool starts_zip = inspect_file(path);
        int code = 0;
        za_ = zip_open(path.c_str(), ZIP_RDONLY, &code);
        if (!za_) {
            const std::string why = libzip_text(code);
            switch (code) {
                case ZIP_ER_NOZIP:
                    bad(starts_zip ? "truncated or corrupt ZIP archive (no end-of-central-directory record; " + why + ")"
                                   : "not a ZIP archive (" + why + ")");
                case ZIP_ER_INCONS:
                case ZIP_ER_EOF:
                case ZIP_ER_READ:
                case ZIP_ER_SEEK: bad("truncated or corrupt ZIP archive (" + why + ")");
                case ZIP_ER_MULTIDISK: bad("multi-disk ZIP archives are not supported (" + why + ")");
                case ZIP_ER_MEMORY: throw std::bad_alloc();
                default: bad("cannot open it as a ZIP archive (" + why + ")");
            }
        }
        const zip_int64_t n = zip_get_num_entries(za_, 0);
        for (zip_int64_t i = 0; i < n; ++i) {
            const char* name = zip_get_name(za_, static_cast<zip_uint64_t>(i), ZIP_FL_ENC_RAW);
            if (!name) bad("corrupt ZIP archive: entry " + std::to_string(i) + " has no name (" +
                           libzip_text(zip_get_error(za_)) + ")");
            names_.emplace_back(name);
        }
    }
    ~Archive() { zip_discard(za_); }
    Archive(const Archive&) = delete;
    Archive& operator=(const Archive&) = delete;

    // The index of entry `name`; errors when it is missing (naming what there is) or appears twice.
    zip_uint64_t find(const std::string& name) const {
        std::size_t found = names_.size();
        for (std::size_t i = 0; i < names_.size(); ++i) {
            if (names_[i] != name) continue;
            if (found != names_.size()) bad("corrupt archive: it holds two entries named '" + name + "'");
            found = i;
        }
        if (found == names_.size()) {
            std::string list;
            for (const std::string& n : names_) list += (list.empty() ? "" : ", ") + n;
            bad("missing array '" + name + "': not a scipy.sparse CSR matrix file (the archive holds " +
                (list.empty() ? "no entries" : list) + ")");
        }
        return found;
    }

    // The entry's size (after inflating) and checks of what libzip would otherwise accept.
    zip_uint64_t check_entry(zip_uint64_t index) const {
        const std::string what = "entry '" + names_[index] + "'";
        zip_stat_t st;
        zip_stat_init(&st);
        if (zip_stat_index(za_, index, 0, &st) != 0)
            bad("corrupt ZIP archive: " + what + " (" + libzip_text(zip_get_error(za_)) + ")");
        const zip_uint64_t need = ZIP_STAT_SIZE | ZIP_STAT_COMP_SIZE | ZIP_STAT_COMP_METHOD | ZIP_STAT_CRC;
        if ((st.valid & need) != need) bad("corrupt ZIP archive: " + what + " lacks its sizes or CRC-32");
        if ((st.valid & ZIP_STAT_ENCRYPTION_METHOD) && st.encryption_method != ZIP_EM_NONE) bad(what + " is encrypted");
        if (st.comp_method != ZIP_CM_STORE && st.comp_method != ZIP_CM_DEFLATE)
            bad(what + " uses compression method " + std::to_string(st.comp_method) +
                " (only stored and deflate are supported)");
        if (st.comp_method == ZIP_CM_STORE && st.comp_size != st.size)
            bad("corrupt ZIP archive: stored " + what + " has compressed size " + std::to_string(st.comp_size) +
                " != size " + std::to_string(st.size));
        if (st.comp_method == ZIP_CM_DEFLATE && st.size > st.comp_size * 1032 + 1024)  // deflate expands at most 1032:1
            bad("corrupt ZIP archive: " + what + " claims " + std::to_string(st.size) + " bytes from " +
                std::to_string(st.comp_size) + " compressed bytes");
        crc_ = st.crc;
        return st.size;
    }

    // Streams the uncompressed bytes of an entry to `sink`; libzip verifies its size and CRC-32.
    void extract(zip_uint64_t index, const std::function<void(const std::uint8_t*, std::size_t)>& sink) const {
        const std::string what = "entry '" + names_[index] + "'";
        const zip_uint64_t size = check_entry(index);
        zip_file_t* f = zip_fopen_index(za_, index, 0);
        if (!f) entry_error(what, zip_get_error(za_));
        std::unique_ptr<zip_file_t, int (*)(zip_file_t*)> close(f, zip_fclose);
        std::vector<std::uint8_t> buf(static_cast<std::size_t>(std::min<zip_uint64_t>(kChunk, size + 1)));
        zip_uint64_t produced = 0;
        for (;;) {
            const zip_int64_t n = zip_fread(f, buf.data(), buf.size());
            if (n < 0) entry_error(what, zip_file_get_error(f));
            if (n == 0) break;
            produced += static_cast<zip_uint64_t>(n);
            if (produced > size)
                bad("corrupt ZIP archive: " + what + " holds more than its recorded " + std::to_string(size) + " bytes");
            sink(buf.data(), static_cast<std::size_t>(n));
        }
        if (produced != size)
            bad("corrupt ZIP archive: " + what + " holds " + std::to_string(produced) + " bytes, its header says " +
                std::to_string(size));
    }

    const std::string& name(zip_uint64_t index) const { return names_[index]; }

private:
    // libzip's error while reading an entry, in the words of io/LtmFile.h.
    [[noreturn]] void entry_error(const std::string& what, const zip_error_t* e) const {
        const std::string why = libzip_text(e);
        switch (zip_error_code_zip(e)) {
            case ZIP_ER_CRC:
                bad("CRC-32 mismatch in " + what + " (recorded " + hex32(crc_) + "; " + why + "): the file is corrupt");
            case ZIP_ER_COMPRESSED_DATA:
            case ZIP_ER_ZLIB: bad("corrupt ZIP archive: bad deflate data in " + what + " (" + why + ")");
            case ZIP_ER_ENCRNOTSUPP:
            case ZIP_ER_NOPASSWD:
            case ZIP_ER_WRONGPASSWD: bad(what + " is encrypted (" + why + ")");
            case ZIP_ER_COMPNOTSUPP: bad(what + " uses an unsupported compression method (" + why + ")");
            case ZIP_ER_MEMORY: throw std::bad_alloc();
            default: bad("truncated or corrupt archive: cannot read " + what + " (" + why + ")");
        }
    }

    zip_t* za_ = nullptr;
    std::vector<std::string> names_;
    mutable std::uint32_t crc_ = 0;  // of the entry being read (for messages)
};

// Consumes the bytes of one .npy entry: the header, then whole elements passed to on_elements.
class NpyStream {
public:
    using OnHeader = std::function<void(io::NpyHeader&)>;
    using OnElements = std::function<void(const std::uint8_t*, std::size_t count)>;

    NpyStream(std::string entry, std::uint64_t entry_size, OnHeader on_header, OnElements on_elements)
        : entry_(std::move(entry)), entry_size_(entry_size), on_header_(std::move(on_header)),
          on_elements_(std::move(on_elements)) {}

    void feed(const std::uint8_t* p, std::size_t n) {
        while (!have_header_ && n > 0) {
            const std::size_t m = std::min(n, want_ - head_.size());
            head_.append(reinterpret_cast<const char*>(p), m);
            p += m;
            n -= m;
            if (head_.size() == want_) advance();
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
    // The preamble is gathered in steps (io::npy_preamble_size): magic and version, the header
    // length, then the whole header, which is parsed.
    void advance() {
        try {
            const std::size_t want = io::npy_preamble_size(head_);
            if (want != want_) {
                want_ = want;
                return;
            }
            info_ = io::parse_npy_preamble(head_);
        } catch (const io::NpyError& e) {
            bad("corrupt array " + entry_ + ": " + e.what());
        }
        const std::uint64_t payload = entry_size_ - std::min<std::uint64_t>(entry_size_, info_.preamble_size);
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
    std::size_t want_ = io::npy_preamble_size({});
    bool have_header_ = false;
    io::NpyHeader info_;
    std::vector<std::uint8_t> carry_;
    std::uint64_t done_ = 0;
};

using io::npy_load_float;
using io::npy_load_uint;

std::int64_t load_int(const std::uint8_t* p, std::size_t size, bool big) {
    const std::uint64_t u = npy_load_uint(p, size, big);
    if (size == 8) return static_cast<std::int64_t>(u);
    const std::uint64_t sign = std::uint64_t(1) << (8 * size - 1);
    return static_cast<std::int64_t>((u ^ sign)) - static_cast<std::int64_t>(sign);
}

// Reads one array entry; `on_header` validates dtype and shape (throwing), `on_elements` converts.
void read_array(const Archive& zip, const std::string& name, const NpyStream::OnHeader& on_header,
                const NpyStream::OnElements& on_elements) {
    const zip_uint64_t index = zip.find(name);
    NpyStream npy("'" + name + "'", zip.check_entry(index), on_header, on_elements);
    zip.extract(index, [&](const std::uint8_t* p, std::size_t n) { npy.feed(p, n); });
    npy.finish();
}

void require_1d(const io::NpyHeader& info, const std::string& name) {
    if (info.shape.size() != 1)
        bad("bad shape of array '" + name + "': it has " + std::to_string(info.shape.size()) +
            " dimensions, expected 1");
}

CsrMatrix read_npz(const Archive& zip) {
    CsrMatrix T;

    // format: a bytes or str scalar "csr"
    std::string format;
    {
        io::NpyHeader fi;
        read_array(
            zip, "format.npy",
            [&](io::NpyHeader& info) {
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
                        const auto c = static_cast<std::uint32_t>(npy_load_uint(p + i, 4, fi.big_endian));
                        if (c) format.push_back(c < 128 ? static_cast<char>(c) : '?');
                    }
                }
            });
    }
    if (format != "csr") bad("it holds a sparse matrix in format '" + format + "', not a CSR matrix");

    for (const char* name : {"shape.npy", "indptr.npy", "indices.npy", "data.npy"}) zip.find(name);

    // shape: two non-negative integers
    std::vector<std::int64_t> shape;
    {
        io::NpyHeader si;
        read_array(
            zip, "shape.npy",
            [&](io::NpyHeader& info) {
                if ((info.kind != 'i' && info.kind != 'u') || (info.itemsize != 4 && info.itemsize != 8))
                    bad("bad dtype '" + info.descr + "' of array 'shape.npy' (expected int64 or int32)");
                if (info.shape != std::vector<std::uint64_t>{2})
                    bad("bad shape of array 'shape.npy': expected (2,), a matrix shape");
                si = info;
            },
            [&](const std::uint8_t* p, std::size_t count) {
                for (std::size_t i = 0; i < count; ++i) {
                    const std::uint8_t* q = p + i * si.itemsize;
                    if (si.kind == 'u' && si.itemsize == 8 && npy_load_uint(q, 8, si.big_endian) > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
                        bad("matrix shape entry too large in 'shape.npy'");
                    shape.push_back(si.kind == 'u' ? static_cast<std::int64_t>(npy_load_uint(q, si.itemsize, si.big_endian))
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
        io::NpyHeader ii;
        read_array(
            zip, "indptr.npy",
            [&](io::NpyHeader& info) {
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
        io::NpyHeader ii;
        read_array(
            zip, "indices.npy",
            [&](io::NpyHeader& info) {
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
        io::NpyHeader di;
        read_array(
            zip, "data.npy",
            [&](io::NpyHeader& info) {
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
                    const double v = npy_load_float(p + i * di.itemsize, di.itemsize, di.big_endian);
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
        const Archive zip(path);
        return read_npz(zip);
    } catch (const ReadError& e) {
        throw std::runtime_error("cannot read LTM file '" + path + "': " + e.what());
    } catch (const std::bad_alloc&) {
        throw std::runtime_error("cannot read LTM file '" + path + "': out of memory");
    } catch (const std::length_error& e) {
        throw std::runtime_error("cannot read LTM file '" + path + "': implausible array size (" + e.what() + ")");
    }
}

}  // namespace ltm
