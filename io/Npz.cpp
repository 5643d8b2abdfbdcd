#include "io/Npz.h"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>
#include <new>
#include <set>
#include <stdexcept>

#include "io/AtomicFile.h"

namespace ltm::io {


NpyArray npy_bytes_scalar(std::string name, const std::string& bytes) {
    return NpyArray{std::move(name), "|S" + std::to_string(bytes.size()), {}, bytes.data(), bytes.size(), {}};
}

namespace {

constexpr std::uint32_t kSigLocal = 0x04034b50, kSigCentral = 0x02014b50, kSigEnd = 0x06054b50,
                        kSigEnd64 = 0x06064b50, kSigLocator64 = 0x07064b50;
constexpr std::uint64_t k32 = 0xFFFFFFFFull;  // a 32-bit field with this value defers to ZIP64
constexpr std::uint16_t kDosTime = 0, kDosDate = (0 << 9) | (1 << 5) | 1;  // 1980-01-01 00:00:00
constexpr std::size_t kChunk = std::size_t(1) << 20;

constexpr bool kHostLittle = detail::kHostLittle;

void put16(std::string& s, std::uint16_t v) {
    for (int i = 0; i < 2; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put64(std::string& s, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

// Python's repr of a shape tuple: "()", "(N,)", "(A, B)", ...
std::string shape_repr(const std::vector<std::uint64_t>& shape) {
    if (shape.size() == 1) return "(" + std::to_string(shape[0]) + ",)";
    std::string s = "(";
    for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
    return s + ")";
}

// The .npy preamble (format 1.0) for a C-order array. Fails (empty result) when the header does
// not fit version 1.0's 16-bit length, which no shape numpy allows (at most 32 dimensions) reaches.
std::string npy_preamble(const std::string& descr, const std::string& shape) {
    std::string dict = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape + ", }";
    const std::size_t unpadded = 10 + dict.size() + 1;  // magic 6, version 2, length 2, '\n'
    dict.append((64 - unpadded % 64) % 64, ' ');
    dict.push_back('\n');
    if (dict.size() > 0xFFFF) return {};
    std::string out("\x93NUMPY\x01\x00", 8);
    put16(out, static_cast<std::uint16_t>(dict.size()));
    return out + dict;
}

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
    t.swap = !bytewise && (order == '<') != kHostLittle;
    return "";
}

using Sink = NpySink;

struct Deflater {
    z_stream zs{};
    bool live = false;
    ~Deflater() {
        if (live) deflateEnd(&zs);
    }
};

// A streaming ZIP writer: entries are deflated as they are produced; each local header is patched
// with the CRC-32 and sizes once its entry is complete (AtomicFile seeks back), so no data
// descriptors are needed and nothing is buffered beyond one chunk.
class ZipWriter {
public:
    ZipWriter(AtomicFile& file, const NpzWriteOptions& options) : f_(file), opt_(options) {}

    // One deflated entry of exactly `size` bytes, produced by produce(sink).
    void add(const std::string& name, std::uint64_t size, const std::function<void(const Sink&)>& produce) {
        Entry e;
        e.name = name;
        e.offset = f_.tell();
        e.usize = size;
        Deflater d;
        if (deflateInit2(&d.zs, opt_.compression_level, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
            f_.fail("zlib's deflateInit2 failed (compression level " + std::to_string(opt_.compression_level) + ")");
        d.live = true;
        const std::uint64_t bound = deflateBound(&d.zs, static_cast<uLong>(size));
        e.zip64_local = opt_.force_zip64 || size >= k32 || bound >= k32;

        std::string local;
        put32(local, kSigLocal);
        put16(local, e.zip64_local ? 45 : 20);  // version needed: 4.5 for ZIP64, 2.0 for deflate
        put16(local, 0);                         // flags
        put16(local, 8);                         // deflate
        put16(local, kDosTime);
        put16(local, kDosDate);
        put32(local, 0);  // CRC-32, sizes: patched below
        put32(local, 0);
        put32(local, 0);
        put16(local, static_cast<std::uint16_t>(name.size()));
        put16(local, e.zip64_local ? 20 : 0);
        local += name;
        if (e.zip64_local) {
            put16(local, 0x0001);
            put16(local, 16);
            put64(local, 0);
            put64(local, 0);
        }
        f_.write(local.data(), local.size());

        std::vector<unsigned char> out(kChunk);
        std::uint64_t consumed = 0, produced = 0;
        uLong crc = crc32(0L, Z_NULL, 0);
        auto pump = [&](int flush) {
            int ret;
            do {
                d.zs.next_out = out.data();
                d.zs.avail_out = static_cast<uInt>(out.size());
                ret = deflate(&d.zs, flush);
                if (ret == Z_STREAM_ERROR) f_.fail("zlib's deflate failed on entry '" + name + "'");
                const std::size_t have = out.size() - d.zs.avail_out;
                if (have > 0) f_.write(out.data(), have);
                produced += have;
            } while (d.zs.avail_out == 0 || (flush == Z_FINISH && ret != Z_STREAM_END));
        };
        const Sink sink = [&](const void* p, std::size_t n) {
            const auto* bytes = static_cast<const unsigned char*>(p);
            while (n > 0) {
                const std::size_t m = std::min<std::size_t>(n, std::size_t(1) << 30);
                crc = crc32_z(crc, bytes, m);
                d.zs.next_in = const_cast<unsigned char*>(bytes);
                d.zs.avail_in = static_cast<uInt>(m);
                pump(Z_NO_FLUSH);
                bytes += m;
                n -= m;
                consumed += m;
            }
        };
        produce(sink);
        d.zs.next_in = nullptr;
        d.zs.avail_in = 0;
        pump(Z_FINISH);
        if (consumed != size)
            f_.fail("entry '" + name + "' was given " + std::to_string(consumed) + " bytes, but its shape and dtype need " +
                    std::to_string(size));
        e.crc = static_cast<std::uint32_t>(crc);
        e.csize = produced;

        const std::uint64_t end = f_.tell();
        std::string patch;
        put32(patch, e.crc);
        put32(patch, e.zip64_local ? static_cast<std::uint32_t>(k32) : static_cast<std::uint32_t>(e.csize));
        put32(patch, e.zip64_local ? static_cast<std::uint32_t>(k32) : static_cast<std::uint32_t>(e.usize));
        f_.seek(e.offset + 14);
        f_.write(patch.data(), patch.size());
        if (e.zip64_local) {
            std::string sizes;
            put64(sizes, e.usize);
            put64(sizes, e.csize);
            f_.seek(e.offset + 30 + name.size() + 4);
            f_.write(sizes.data(), sizes.size());
        }
        f_.seek(end);
        entries_.push_back(e);
    }

    // The central directory and the end records (ZIP64 where needed).
    void finish() {
        const std::uint64_t cd_offset = f_.tell();
        const bool force = opt_.force_zip64;
        std::string cd;
        for (const Entry& e : entries_) {
            const bool big_u = force || e.usize >= k32, big_c = force || e.csize >= k32,
                       big_o = force || e.offset >= k32;
            std::string extra;
            if (big_u || big_c || big_o) {
                std::string fields;
                if (big_u) put64(fields, e.usize);
                if (big_c) put64(fields, e.csize);
                if (big_o) put64(fields, e.offset);
                put16(extra, 0x0001);
                put16(extra, static_cast<std::uint16_t>(fields.size()));
                extra += fields;
            }
            const std::uint16_t version = (e.zip64_local || !extra.empty()) ? 45 : 20;
            put32(cd, kSigCentral);
            put16(cd, version);  // made by: MS-DOS host (attributes unused), spec version
            put16(cd, version);  // needed
            put16(cd, 0);
            put16(cd, 8);
            put16(cd, kDosTime);
            put16(cd, kDosDate);
            put32(cd, e.crc);
            put32(cd, big_c ? static_cast<std::uint32_t>(k32) : static_cast<std::uint32_t>(e.csize));
            put32(cd, big_u ? static_cast<std::uint32_t>(k32) : static_cast<std::uint32_t>(e.usize));
            put16(cd, static_cast<std::uint16_t>(e.name.size()));
            put16(cd, static_cast<std::uint16_t>(extra.size()));
            put16(cd, 0);  // comment length
            put16(cd, 0);  // disk number start
            put16(cd, 0);  // internal attributes
            put32(cd, 0);  // external attributes
            put32(cd, big_o ? static_cast<std::uint32_t>(k32) : static_cast<std::uint32_t>(e.offset));
            cd += e.name;
            cd += extra;
        }
        f_.write(cd.data(), cd.size());
        const std::uint64_t cd_size = cd.size(), n = entries_.size();
        const bool big_n = force || n >= 0xFFFF, big_size = force || cd_size >= k32,
                   big_off = force || cd_offset >= k32;
        std::string tail;
        if (big_n || big_size || big_off) {
            const std::uint64_t record = f_.tell();
            put32(tail, kSigEnd64);
            put64(tail, 44);  // size of the remaining record
            put16(tail, 45);
            put16(tail, 45);
            put32(tail, 0);  // this disk
            put32(tail, 0);  // disk with the central directory
            put64(tail, n);
            put64(tail, n);
            put64(tail, cd_size);
            put64(tail, cd_offset);
            put32(tail, kSigLocator64);
            put32(tail, 0);  // disk with the ZIP64 end record
            put64(tail, record);
            put32(tail, 1);  // total number of disks
        }
        put32(tail, kSigEnd);
        put16(tail, 0);
        put16(tail, 0);
        put16(tail, big_n ? 0xFFFF : static_cast<std::uint16_t>(n));
        put16(tail, big_n ? 0xFFFF : static_cast<std::uint16_t>(n));
        put32(tail, big_size ? static_cast<std::uint32_t>(k32) : static_cast<std::uint32_t>(cd_size));
        put32(tail, big_off ? static_cast<std::uint32_t>(k32) : static_cast<std::uint32_t>(cd_offset));
        put16(tail, 0);  // comment length
        f_.write(tail.data(), tail.size());
    }

private:
    struct Entry {
        std::string name;
        std::uint64_t offset = 0, usize = 0, csize = 0;
        std::uint32_t crc = 0;
        bool zip64_local = false;
    };
    AtomicFile& f_;
    NpzWriteOptions opt_;
    std::vector<Entry> entries_;
};

// Streams `bytes` bytes of elements of `itemsize` bytes, reversing each element's bytes, in
// chunks of kChunk.
void emit_swapped(const Sink& sink, const unsigned char* p, std::size_t bytes, std::size_t itemsize) {
    std::vector<unsigned char> buf(std::min(bytes, kChunk / itemsize * itemsize));
    while (bytes > 0) {
        const std::size_t m = std::min(bytes, buf.size());
        for (std::size_t i = 0; i < m; i += itemsize)
            for (std::size_t b = 0; b < itemsize; ++b) buf[i + b] = p[i + itemsize - 1 - b];
        sink(buf.data(), m);
        p += m;
        bytes -= m;
    }
}

struct Checked {
    std::string preamble;
    Dtype dtype;
};

void write_archive(const std::string& path, const std::vector<NpyArray>& arrays, const NpzWriteOptions& options,
                   const std::string& kind) {
    const auto fail = [&](const std::string& why) {
        throw std::runtime_error("cannot write " + kind + " '" + path + "': " + why);
    };
    if (options.compression_level < 0 || options.compression_level > 9)
        fail("compression level " + std::to_string(options.compression_level) + " is outside 0..9");

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
            fail(what + " has " + std::to_string(a.bytes) + " bytes, but its shape " + shape_repr(a.shape) +
                 " of '" + a.descr + "' needs " + std::to_string(count) + " x " + std::to_string(c.dtype.itemsize));
        if (a.bytes > 0 && a.data == nullptr && !a.produce) fail(what + " has no data");
        c.preamble = npy_preamble(a.descr, shape_repr(a.shape));
        if (c.preamble.empty()) fail(what + ": the .npy header is too long (too many dimensions)");
    }

    AtomicFile file(path, kind);
    ZipWriter zip(file, options);
    for (std::size_t k = 0; k < arrays.size(); ++k) {
        const NpyArray& a = arrays[k];
        const Checked& c = checked[k];
        zip.add(a.name + ".npy", c.preamble.size() + static_cast<std::uint64_t>(a.bytes), [&](const Sink& sink) {
            sink(c.preamble.data(), c.preamble.size());
            if (a.produce) {
                // The sink's own failures (writing the file) are complete messages already.
                bool sink_failed = false;
                const Sink guarded = [&](const void* p, std::size_t n) {
                    try {
                        sink(p, n);
                    } catch (...) {
                        sink_failed = true;
                        throw;
                    }
                };
                try {
                    a.produce(guarded);
                } catch (const std::exception& e) {
                    if (sink_failed) throw;
                    file.fail("array '" + a.name + "': " + e.what());
                }
                return;
            }
            if (a.bytes == 0) return;
            if (c.dtype.swap)
                emit_swapped(sink, static_cast<const unsigned char*>(a.data), a.bytes, c.dtype.itemsize);
            else
                sink(a.data, a.bytes);
        });
    }
    zip.finish();
    file.commit();
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
