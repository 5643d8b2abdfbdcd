#include "io/Npz.h"

#include <isa-l/igzip_lib.h>
#include <zip.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <new>
#include <set>
#include <stdexcept>

#include "io/AtomicFile.h"
#include "io/Deflate.h"
#include "io/Npy.h"

namespace ltm::io {

NpyArray npy_bytes_scalar(std::string name, const std::string& bytes) {
    return NpyArray{std::move(name), "|S" + std::to_string(bytes.size()), {}, bytes.data(), bytes.size(), {}};
}

namespace {

// 1980-01-01 00:00:00 as a DOS date and time: the earliest a ZIP header can hold.
constexpr zip_uint16_t kDosTime = 0, kDosDate = (0 << 9) | (1 << 5) | 1;

// What a descr says, or why it is not supported ("" when it is).
struct Dtype {
    std::size_t itemsize = 0;
    bool swap = false;  // the descr's byte order differs from the host's
};
std::string parse_descr(const std::string& d, Dtype& t) {
    const std::string supported = "supported are '|b1', '<i1'..'<i8', '<u1'..'<u8', '<f2', '<f4', '<f8' "
                                  "(or '>' for big-endian; '|' for one byte) and '|S<n>'";
    if (d.size() < 3) return "unsupported dtype '" + d + "'; " + supported;
    const char order = d[0], kind = d[1];
    std::size_t n = 0;
    for (std::size_t i = 2; i < d.size(); ++i) {
        if (d[i] < '0' || d[i] > '9' || n > 1000000) return "unsupported dtype '" + d + "'; " + supported;
        n = n * 10 + static_cast<std::size_t>(d[i] - '0');
    }
    bool ok = false;
    switch (kind) {
        case 'b': ok = n == 1; break;
        case 'i':
        case 'u': ok = n == 1 || n == 2 || n == 4 || n == 8; break;
        case 'f': ok = n == 2 || n == 4 || n == 8; break;
        case 'S': ok = n >= 1; break;
        default: break;
    }
    if (!ok) return "unsupported dtype '" + d + "'; " + supported;
    const bool bytewise = n == 1 || kind == 'S';
    if (bytewise ? order != '|' : order != '<' && order != '>')
        return "dtype '" + d + "' has the wrong byte-order character: " +
               (bytewise ? "'|' for single bytes and byte strings" : "'<' or '>' for multi-byte numbers");
    t.itemsize = n;
    t.swap = !bytewise && (order == '<') != detail::kHostLittle;
    return "";
}

// The first failure inside a libzip callback. Callbacks are C: they must not throw, so they record
// why they failed here and return -1; write_archive reports it once libzip has given up.
struct Failure {
    std::exception_ptr error;  // a complete "cannot write ..." error (AtomicFile's)
    std::string reason;        // or the reason to report through AtomicFile::fail
    bool any() const { return error || !reason.empty(); }
};

// The archive's destination for libzip: a write source (zip_source_function) backed by an
// io::AtomicFile.
//
// Why a streaming write source rather than building the archive in a zip_source_buffer and writing
// those bytes through AtomicFile afterwards: a T of a large render is several GB compressed, and a
// buffer would hold the whole archive in memory on top of the matrix. Here libzip writes each
// entry's compressed bytes to the file as it produces them (seeking back to finish each local
// header), so the memory beyond the matrix is libzip's few-KiB buffers. libzip's own temporary
// file and rename (zip_open by name) are never used: AtomicFile is the one atomic writer, and its
// commit happens after zip_close, not inside libzip.
//
// libzip only creates (the source reports that no archive exists yet, so nothing is ever read
// back) and then calls BEGIN_WRITE, WRITE / SEEK_WRITE / TELL_WRITE, COMMIT_WRITE (or
// ROLLBACK_WRITE after a failure).
struct ArchiveSink {
    AtomicFile& file;
    Failure& failure;
    zip_error_t error;
    std::uint64_t end = 0;  // bytes written so far (the file's size)
    bool complete = false;  // libzip committed: the archive is whole

    ArchiveSink(AtomicFile& f, Failure& fl) : file(f), failure(fl) { zip_error_init(&error); }
    ~ArchiveSink() { zip_error_fini(&error); }

    static zip_int64_t callback(void* state, void* data, zip_uint64_t len, zip_source_cmd_t cmd) {
        auto& s = *static_cast<ArchiveSink*>(state);
        switch (cmd) {
            case ZIP_SOURCE_SUPPORTS: return ZIP_SOURCE_SUPPORTS_WRITABLE;
            case ZIP_SOURCE_STAT:  // "no such archive": libzip creates a new one
                zip_error_set(&s.error, ZIP_ER_READ, ENOENT);
                return -1;
            case ZIP_SOURCE_BEGIN_WRITE:
                s.file.seek(0);
                s.end = 0;
                return 0;
            case ZIP_SOURCE_WRITE:
                try {
                    s.file.write(data, static_cast<std::size_t>(len));
                } catch (...) {
                    if (!s.failure.any()) s.failure.error = std::current_exception();
                    zip_error_set(&s.error, ZIP_ER_WRITE, errno);
                    return -1;
                }
                s.end = std::max(s.end, s.file.tell());
                return static_cast<zip_int64_t>(len);
            case ZIP_SOURCE_SEEK_WRITE: {
                const zip_int64_t to = zip_source_seek_compute_offset(s.file.tell(), s.end, data, len, &s.error);
                if (to < 0) return -1;
                s.file.seek(static_cast<std::uint64_t>(to));
                return 0;
            }
            case ZIP_SOURCE_TELL_WRITE: return static_cast<zip_int64_t>(s.file.tell());
            case ZIP_SOURCE_COMMIT_WRITE: s.complete = true; return 0;
            case ZIP_SOURCE_ROLLBACK_WRITE: return 0;  // the AtomicFile removes its temporary
            case ZIP_SOURCE_ERROR: return zip_error_to_data(&s.error, data, len);
            case ZIP_SOURCE_FREE: return 0;  // owned by write_archive
            default:  // OPEN, READ, SEEK, TELL, CLOSE, REMOVE: there is nothing to read or remove
                zip_error_set(&s.error, ZIP_ER_OPNOTSUPP, 0);
                return -1;
        }
    }
};

// ISA-L's igzip (Debian's libisal, BSD-3-Clause) deflating one entry at a time: the entries' raw
// deflate streams (ZIP method 8) and their CRC-32s, made here rather than by libzip's zlib.
//
// Why: zlib's level 1, libzip's own deflate, would be the write stage's largest cost at scale (a
// 1000 x 1000 camera against a 2000 x 2000 display: 1.1 s of one core for ltm.npz's 126 MB, 0.9 s
// for features.npz's 68 MB), and igzip's level 2 deflates the same arrays about four times as fast, within 10 % of zlib's
// size (io/LtmFile.h, docs/benchmarks.md). libzip stays the archive writer: an entry source whose
// stat says its bytes are deflated already is copied as it is (libzip 1.7's add_data: no
// recompression when the source's method is the entry's), with the CRC-32 and size the stat gives
// once the last byte is read.
//
// The bytes depend on the input, the level and ISA-L's version, never on the thread or the run
// (start() zeroes the state). ISA-L picks its kernels by the CPU's instruction sets, so another
// kind of CPU may deflate the same arrays into other bytes, which inflate to the same arrays.
struct Deflater {
    int level = 1;                          // igzip's level, 1..3 (NpzWriteOptions::compression_level)
    isal_zstream z{};
    ScratchBytes level_buf;                 // igzip's working memory for `level`: level_size bytes
    std::size_t level_size = 0;             // (its default size)
    ScratchBytes out;                       // deflated bytes not yet handed to libzip: [head, tail)
    std::size_t head = 0, tail = 0;
    std::uint32_t crc = 0;                  // CRC-32 of the input so far (ZIP's, as zlib's crc32)

    // Input is fed in pieces of this size: the CRC-32 and the deflate read each piece while it is
    // in the cache.
    static constexpr std::size_t kPiece = 256 * 1024;

    // The working memory and the output piece are the thread's, kept from its last archive:
    // fresh ones for every archive faulted half a megabyte of new pages in each (two archives a
    // render, and tens of thousands in a dataset). They are borrowed while the deflater lives and
    // given back after; an archive begun on a thread while another is open there gets fresh ones.
    // Both are io::ScratchBytes: in huge pages, since a first archive's 0.6 MB of fresh small
    // pages cost about 1.5 ms of faults (a render writes two, on two threads).
    explicit Deflater(int lvl) : level(lvl), level_size(igzip_level_buffer_size(lvl)) {  // checks lvl: 1..3
        Kept& k = kept();
        level_buf.swap(k.level_buf[lvl]);
        out.swap(k.out);
        level_buf.get(level_size);  // cleared by start() for each entry
        out.get(kPiece);
    }
    ~Deflater() {
        Kept& k = kept();
        k.level_buf[level].swap(level_buf);
        k.out.swap(out);
    }
    Deflater(const Deflater&) = delete;
    Deflater& operator=(const Deflater&) = delete;
    // A new stream, from a zeroed state and working memory: isal_deflate_init leaves part of the
    // stream's state as it was, and igzip's tables keep the previous stream's traces, which would
    // make an entry's bytes depend on the entries before it (io/Deflate.cpp does the same).
    void start() {
        z = isal_zstream{};
        std::memset(level_buf.get(level_size), 0, level_size);
        isal_deflate_init(&z);
        z.level = static_cast<std::uint32_t>(level);
        z.level_buf = level_buf.get(level_size);
        z.level_buf_size = static_cast<std::uint32_t>(level_size);
        z.gzip_flag = IGZIP_DEFLATE;  // raw deflate, as a ZIP entry holds it
        z.flush = NO_FLUSH;
        head = tail = 0;
        crc = 0;
    }
    bool finished() const { return z.internal_state.state == ZSTATE_END && head == tail; }

private:
    struct Kept {
        ScratchBytes level_buf[kIgzipMaxLevel + 1];
        ScratchBytes out;
    };
    static Kept& kept() {
        thread_local Kept k;
        return k;
    }
};

// From this size on, a deflated entry gets a ZIP64 local header. libzip decides that header
// before the data from the entry's size and its estimate of zlib's worst case (size + 5 bytes per
// 16 KiB + 6, zip_close.c), which igzip can exceed by a few hundred bytes on incompressible data
// (tests/io_npz.cpp measures under 0.1 %): an entry just below 4 GiB could then no longer be
// finished. Below 4e9 bytes even 7 % of growth stays within 32-bit sizes.
constexpr std::uint64_t kZip64Entry = 4000000000;

// One entry's bytes for libzip to pull: the .npy preamble, then the array's data (viewed, swapped
// to the descr's byte order, or from NpyArray::fill); deflated on the way when `deflater` is set.
struct EntrySource {
    const NpyArray& array;
    std::string entry, preamble;
    Dtype dtype;
    Failure& failure;
    Deflater* deflater;  // nullptr: stored (ZIP method 0), libzip computes the CRC-32
    zip_error_t error;
    std::uint64_t pos = 0;
    std::vector<unsigned char> staging;  // a piece of input that is not in memory as it is

    EntrySource(const NpyArray& a, std::string p, Dtype d, Failure& f, Deflater* def)
        : array(a), entry(a.name + ".npy"), preamble(std::move(p)), dtype(d), failure(f), deflater(def) {
        zip_error_init(&error);
    }
    ~EntrySource() { zip_error_fini(&error); }

    std::uint64_t size() const { return preamble.size() + static_cast<std::uint64_t>(array.bytes); }

    // Up to n bytes at pos; throws (a message without the file's name) on failure.
    std::size_t read(unsigned char* out, std::size_t n) {
        n = static_cast<std::size_t>(std::min<std::uint64_t>(n, size() - pos));
        std::size_t done = 0;
        if (pos < preamble.size()) {
            done = std::min(n, static_cast<std::size_t>(preamble.size() - pos));
            std::memcpy(out, preamble.data() + pos, done);
        }
        const std::uint64_t at = pos + done - preamble.size();  // offset in the array's data
        const std::size_t want = n - done;
        if (want > 0) {
            if (array.fill) {
                std::size_t got = 0;
                try {
                    got = array.fill(at, out + done, want);
                } catch (const std::exception& e) {
                    throw std::runtime_error("array '" + array.name + "': " + e.what());
                }
                if (got > want) throw std::runtime_error("array '" + array.name + "': its fill overran the buffer");
                if (got < want)
                    throw std::runtime_error("entry '" + entry + "' was given " + std::to_string(pos + done + got) +
                                             " bytes, but its shape and dtype need " + std::to_string(size()));
            } else {
                const auto* data = static_cast<const unsigned char*>(array.data);
                if (!dtype.swap) {
                    std::memcpy(out + done, data + at, want);
                } else {  // byte b of an element in the file is byte itemsize - 1 - b in memory
                    const std::size_t is = dtype.itemsize;
                    for (std::size_t i = 0; i < want; ++i) {
                        const std::uint64_t k = at + i;
                        out[done + i] = data[k - k % is + (is - 1 - k % is)];
                    }
                }
            }
        }
        pos += n;
        return n;
    }

    // The next piece of the entry's input from pos (a view of the preamble or of the array's
    // data where they hold the file's bytes, else `staging` filled by read), up to kPiece bytes;
    // empty at the end.
    std::pair<const unsigned char*, std::size_t> next_piece() {
        const std::uint64_t left = size() - pos;
        const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, Deflater::kPiece));
        const unsigned char* p = nullptr;
        std::size_t k = 0;
        if (pos < preamble.size()) {
            p = reinterpret_cast<const unsigned char*>(preamble.data()) + pos;
            k = std::min(n, static_cast<std::size_t>(preamble.size() - pos));
            pos += k;
        } else if (!array.fill && !dtype.swap) {
            p = static_cast<const unsigned char*>(array.data) + (pos - preamble.size());
            k = n;
            pos += k;
        } else {
            staging.resize(Deflater::kPiece);
            k = read(staging.data(), n);
            p = staging.data();
        }
        return {p, k};
    }

    // Up to n deflated bytes (fewer only at the end of the stream).
    std::size_t read_deflated(unsigned char* dst, std::size_t n) {
        Deflater& d = *deflater;
        std::size_t done = 0;
        while (done < n) {
            if (d.head == d.tail) {
                if (d.z.internal_state.state == ZSTATE_END) break;
                // Refill `out`: deflate until it is full or the stream has ended.
                d.head = d.tail = 0;
                d.z.next_out = d.out.get(Deflater::kPiece);
                d.z.avail_out = static_cast<std::uint32_t>(Deflater::kPiece);
                while (d.z.avail_out > 0 && d.z.internal_state.state != ZSTATE_END) {
                    if (d.z.avail_in == 0 && !d.z.end_of_stream) {
                        const auto [p, k] = next_piece();
                        d.crc = crc32(d.crc, p, k);
                        d.z.next_in = const_cast<std::uint8_t*>(p);  // igzip only reads it
                        d.z.avail_in = static_cast<std::uint32_t>(k);
                        d.z.end_of_stream = pos == size();
                    }
                    const int r = isal_deflate(&d.z);
                    if (r != COMP_OK) throw std::runtime_error("ISA-L's deflate failed (code " + std::to_string(r) + ")");
                }
                d.tail = Deflater::kPiece - d.z.avail_out;
            }
            const std::size_t m = std::min(n - done, d.tail - d.head);
            std::memcpy(dst + done, d.out.get(Deflater::kPiece) + d.head, m);
            d.head += m;
            done += m;
        }
        return done;
    }

    static zip_int64_t callback(void* state, void* data, zip_uint64_t len, zip_source_cmd_t cmd) {
        auto& s = *static_cast<EntrySource*>(state);
        switch (cmd) {
            case ZIP_SOURCE_SUPPORTS: return ZIP_SOURCE_SUPPORTS_READABLE;
            case ZIP_SOURCE_OPEN:
                s.pos = 0;
                if (s.deflater) s.deflater->start();
                return 0;
            case ZIP_SOURCE_READ:
                try {
                    const auto n = static_cast<std::size_t>(len);
                    auto* out = static_cast<unsigned char*>(data);
                    return static_cast<zip_int64_t>(s.deflater ? s.read_deflated(out, n) : s.read(out, n));
                } catch (const std::bad_alloc&) {
                    if (!s.failure.any()) s.failure.reason = "out of memory";
                } catch (const std::exception& e) {
                    if (!s.failure.any()) s.failure.reason = e.what();
                }
                zip_error_set(&s.error, ZIP_ER_READ, 0);
                return -1;
            case ZIP_SOURCE_CLOSE: return 0;
            case ZIP_SOURCE_STAT: {
                auto* st = ZIP_SOURCE_GET_ARGS(zip_stat_t, data, len, &s.error);
                if (!st) return -1;
                zip_stat_init(st);
                // Before the data, a deflated entry's size is given only below kZip64Entry: libzip
                // gives an entry of unknown size a ZIP64 local header.
                if (!s.deflater || s.size() < kZip64Entry || s.pos == s.size()) {
                    st->valid |= ZIP_STAT_SIZE;
                    st->size = s.size();
                }
                if (s.deflater) {
                    // Deflated already (libzip copies the bytes); the CRC-32 once all are read.
                    st->valid |= ZIP_STAT_COMP_METHOD;
                    st->comp_method = ZIP_CM_DEFLATE;
                    if (s.deflater->finished() && s.pos == s.size()) {
                        st->valid |= ZIP_STAT_CRC;
                        st->crc = s.deflater->crc;
                    }
                }
                return sizeof(*st);
            }
            case ZIP_SOURCE_ERROR: return zip_error_to_data(&s.error, data, len);
            case ZIP_SOURCE_FREE: return 0;  // owned by write_archive
            default: zip_error_set(&s.error, ZIP_ER_OPNOTSUPP, 0); return -1;
        }
    }
};

struct Checked {
    std::string preamble;
    Dtype dtype;
};

std::string libzip_text(zip_error_t* e) { return std::string("libzip: ") + zip_error_strerror(e); }

void write_archive(const std::string& path, const std::vector<NpyArray>& arrays, const NpzWriteOptions& options,
                   const std::string& kind) {
    const auto fail = [&](const std::string& why) {
        throw std::runtime_error("cannot write " + kind + " '" + path + "': " + why);
    };
    const int level = options.compression_level;
    if (level < 0 || level > kIgzipMaxLevel)
        fail("compression level " + std::to_string(level) + " is outside 0.." + std::to_string(kIgzipMaxLevel));

    std::vector<Checked> checked(arrays.size());
    std::set<std::string> names;
    for (std::size_t k = 0; k < arrays.size(); ++k) {
        const NpyArray& a = arrays[k];
        if (a.name.empty()) fail("array " + std::to_string(k) + " has an empty name");
        if (a.name.size() + 4 > 0xFFFF) fail("the name of array " + std::to_string(k) + " is too long for ZIP");
        const std::string what = "array '" + a.name + "'";
        if (!names.insert(a.name).second) fail("two arrays are named '" + a.name + "'");
        Checked& c = checked[k];
        const std::string bad_descr = parse_descr(a.descr, c.dtype);
        if (!bad_descr.empty()) fail(what + ": " + bad_descr);
        std::uint64_t count = 1;
        for (std::uint64_t s : a.shape) {
            if (s != 0 && count > std::numeric_limits<std::uint64_t>::max() / s) fail(what + ": the shape is too large");
            count *= s;
        }
        if (count > std::numeric_limits<std::uint64_t>::max() / c.dtype.itemsize ||
            count * c.dtype.itemsize != a.bytes)
            fail(what + " has " + std::to_string(a.bytes) + " bytes, but its shape " + npy_shape_repr(a.shape) +
                 " of '" + a.descr + "' needs " + std::to_string(count) + " x " + std::to_string(c.dtype.itemsize));
        if (a.bytes > 0 && a.data == nullptr && !a.fill) fail(what + " has no data");
        try {
            c.preamble = npy_preamble(a.descr, a.shape);
        } catch (const NpyError& e) {
            fail(what + ": " + e.what());
        }
    }

    AtomicFile file(path, kind);
    if (arrays.empty()) {
        // libzip removes an archive without entries instead of writing one: the end record alone.
        file.write(std::string("PK\x05\x06", 4) + std::string(18, '\0'));
        file.commit(options.group);
        return;
    }

    Failure failure;
    ArchiveSink sink(file, failure);
    // libzip writes the entries one after another: one deflater serves them all (it outlives
    // the archive handle, which may call back into the sources until it is discarded).
    std::unique_ptr<Deflater> deflater = level > 0 ? std::make_unique<Deflater>(level) : nullptr;
    std::vector<std::unique_ptr<EntrySource>> entries;
    zip_error_t error;
    zip_error_init(&error);
    const auto libzip_failed = [&](zip_error_t* e) {
        const std::string text = libzip_text(e);
        zip_error_fini(&error);
        file.fail(text);
    };
    zip_source_t* target = zip_source_function_create(&ArchiveSink::callback, &sink, &error);
    if (!target) libzip_failed(&error);
    zip_t* za = zip_open_from_source(target, ZIP_CREATE | ZIP_TRUNCATE, &error);
    if (!za) {
        zip_source_free(target);
        libzip_failed(&error);
    }
    // Until zip_close succeeds, za owns the sources; any early exit discards it.
    std::unique_ptr<zip_t, void (*)(zip_t*)> open(za, zip_discard);
    const auto zip_failed = [&] {
        // Report the callback's own failure if there was one, else libzip's; after discarding the
        // archive, which calls back into the sources one last time.
        const std::string text = libzip_text(zip_get_error(za));
        open.reset();
        zip_error_fini(&error);
        if (failure.error) std::rethrow_exception(failure.error);
        file.fail(failure.reason.empty() ? text : failure.reason);
    };

    for (std::size_t k = 0; k < arrays.size(); ++k) {
        entries.push_back(
            std::make_unique<EntrySource>(arrays[k], checked[k].preamble, checked[k].dtype, failure, deflater.get()));
        EntrySource& e = *entries.back();
        zip_source_t* src = zip_source_function(za, &EntrySource::callback, &e);
        if (!src) zip_failed();
        const zip_int64_t index = zip_file_add(za, e.entry.c_str(), src, ZIP_FL_ENC_UTF_8);
        if (index < 0) {
            zip_source_free(src);
            zip_failed();
        }
        const auto i = static_cast<zip_uint64_t>(index);
        // The entry's method is the source's: libzip neither compresses nor recompresses it.
        if (zip_set_file_compression(za, i, level == 0 ? ZIP_CM_STORE : ZIP_CM_DEFLATE, 0) != 0 ||
            zip_file_set_dostime(za, i, kDosTime, kDosDate, 0) != 0)
            zip_failed();
    }
    if (zip_close(za) != 0) zip_failed();
    open.release();  // zip_close freed it
    zip_error_fini(&error);
    if (failure.any() || !sink.complete) file.fail("internal error: libzip closed an incomplete archive");
    file.commit(options.group);
}

}  // namespace

void write_npz(const std::string& path, const std::vector<NpyArray>& arrays, const NpzWriteOptions& options,
               const std::string& kind) {
    try {
        write_archive(path, arrays, options, kind);
    } catch (const std::bad_alloc&) {
        throw std::runtime_error("cannot write " + kind + " '" + path + "': out of memory");
    }
}

}  // namespace ltm::io
