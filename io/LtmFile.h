#pragma once
// `ltm.npz`: the light transport matrix on disk, in the format of scipy.sparse.save_npz, so that
// `scipy.sparse.load_npz("ltm.npz")` returns it as a scipy.sparse.csr_matrix (float32 values).
//
// What write_ltm_npz writes (byte-for-byte deterministic: the same matrix and options always give
// the same file, on the same kind of CPU; io/Npz.h says why another may deflate differently):
//   An .npz archive (io/Npz.h, which writes it) of five .npy arrays, in this order (the order
//   scipy.sparse.save_npz uses):
//     indices.npy  '<i4', shape (nnz,)      column of each nonzero
//     indptr.npy   '<i4', shape (rows + 1,) when nnz < 2^31, else '<i8' (scipy's own rule)
//     format.npy   '|S3', shape ()          b'csr'
//     shape.npy    '<i8', shape (2,)        (rows, cols)
//     data.npy     '<f4', shape (nnz,)      value of each nonzero
//   Each entry is deflate-compressed (ZIP method 8, raw deflate stream from ISA-L's igzip, io/Npz.h;
//   level 2 by default, see below; level 0 stores, ZIP method 0) with its CRC-32, a fixed timestamp
//   (1980-01-01 00:00) and no extra fields. Each .npy is format version 1.0 (io/Npy.h):
//   "\x93NUMPY" 1 0, a little-endian uint16 header length, and the header
//   "{'descr': '<f4', 'fortran_order': False, 'shape': (N,), }" padded with spaces and ended by
//   '\n' so that the preamble is a multiple of 64 bytes (as numpy pads it); the little-endian array
//   data follows.
//   ZIP64 where libzip needs it (io/Npz.h): sizes, offsets or the central directory beyond 4 GiB
//   get ZIP64 fields and a ZIP64 end record, so files above 4 GiB are written in full (APPNOTE
//   6.3, as Python's zipfile reads). A small file has none.
//
// The default level, 2 of igzip's 1..3, is measured with bench/bench_npz (median of 7 writes
// each, file written and synced; the sizes are deterministic, the times vary with the machine's
// load), with zlib's level 1 deflating the same arrays in the same run for comparison (the
// deflate alone; zlib is what libzip deflates with on its own):
//   T of scenes/paper/bubbles-r1.yaml (10000 x 250000, 63307 nonzeros, 0.55 MB of arrays):
//     level 0 (stored)   547617 bytes  0.003 s
//     level 1            181364 bytes  0.005 s
//     level 2            180453 bytes  0.005 s
//     level 3            173960 bytes  0.006 s
//     zlib level 1       171716 bytes  0.007 s
//   T of scenes/default.yaml (10000 x 250000, 293261 nonzeros, 2.4 MB of arrays; its trace takes
//   about 0.07 s on 2 threads):
//     level 0 (stored)  2387249 bytes  0.010 s
//     level 1            489299 bytes  0.008 s
//     level 2            483307 bytes  0.008 s
//     level 3            454409 bytes  0.013 s
//     zlib level 1       463553 bytes  0.025 s
//   T of scenes/scale.yaml (1000000 x 4000000, 14745723 nonzeros, 122 MB of arrays; 3 writes):
//     level 0 (stored)  121966945 bytes  0.361 s
//     level 1            34842136 bytes  0.358 s
//     level 2            34471092 bytes  0.357 s
//     level 3            33962701 bytes  0.479 s
//     zlib level 1       31325031 bytes  1.411 s
// igzip's levels 1 and 2 write T four times as fast as zlib's level 1 deflates it alone, within
// 5-10 % of its size; level 2 is as fast as level 1 and a little smaller (on features.npz's
// feature images at scale it gives zlib level 1's 23.6 MB, where level 1 gives 24.2 MB); level 3
// is slower for 1-6 % less. The write stage of a render is what users wait for, so level 2 it is; any
// level is read alike (`ltmsim features`, scipy, numpy).

// Writing is atomic (io/AtomicFile.h): libzip streams the archive into a new temporary file in the
// target's folder (".<name>.tmp-<random>"), fsync'ed and renamed onto the path; on any failure the
// temporary is removed and an existing file at the path is left untouched. The matrix is checked
// first (CsrMatrix::check). Errors are std::runtime_error "cannot write LTM file '<path>': ...".
//
// What read_ltm_npz reads (libzip opens the archive; io/Npy.h parses the .npy headers): our files,
// and files written by scipy.sparse.save_npz for a CSR matrix, compressed (the default; numpy
// writes every entry with ZIP64 local headers) or not (compressed=False: ZIP method 0, stored).
// ZIP64 records, data descriptors and archive comments are understood; encrypted entries,
// multi-disk archives and compression methods other than stored and deflate are not (even where
// libzip could read them). Accepted .npy headers: versions 1.0, 2.0 and 3.0, either byte order:
//   data     float32 or float64 (converted to float32; a finite float64 that overflows float32
//            is an error), 1-D
//   indices  int32 or int64 (converted to int32; a value outside int32 is an error), 1-D
//   indptr   int32 or int64, 1-D
//   shape    int32 or int64, shape (2,), non-negative
//   format   a bytes ('|S') or str ('<U') scalar equal to "csr" (anything else, e.g. "csc", is
//            reported as "not a CSR matrix")
// Other entries are ignored (as scipy ignores them). The matrix is then validated by
// CsrMatrix::check, so unsorted or duplicate column indices in a row are rejected (scipy allows
// them; call `T.sum_duplicates()` before saving). Every entry's size and CRC-32 are verified (by
// libzip while inflating, and the size again against the .npy header).
// Errors are std::runtime_error "cannot read LTM file '<path>': <what>", where <what> says what is
// wrong in these words (libzip's own error text follows in parentheses where it found it): no
// such file, it is a folder, the file is empty, a single .npy array, not a ZIP archive, truncated
// or corrupt (ZIP) archive, CRC-32 mismatch in entry '<name>', bad deflate data, encrypted, missing
// array, bad dtype, bad shape, not a CSR matrix, or the CsrMatrix::check message.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "io/Npz.h"
#include "io/CsrMatrix.h"

namespace ltm {

// The compression level (io/Npz.h), under the name this header has always offered.
using NpzWriteOptions = io::NpzWriteOptions;

void write_ltm_npz(const std::string& path, const CsrMatrix& T, const NpzWriteOptions& options = {});

// ltm.npz written from T's rows as they come, block by block, for a T larger than memory: the
// file is byte-identical to write_ltm_npz of the whole matrix (the same arrays, bytes and archive),
// but only the row offsets (8 bytes per row) stay in memory.
//
// How: each block's indices and data are appended to two spill files, which are unnamed files
// (O_TMPFILE) in the target's folder: they never appear in the folder and vanish when closed or
// when the process dies, so a failed or killed render leaves nothing behind (where the file system
// has no O_TMPFILE, a named file ".<name>.spill-<hex>" is created with O_EXCL and unlinked at once,
// to the same effect). They sit beside the target so that the spilled bytes need the disk the
// archive needs, not /tmp's. commit() then writes the archive through write_npz, whose array
// fills read the spill files back as libzip pulls the entries (indices, indptr, format, shape,
// data: the order of write_ltm_npz), into an AtomicFile: atomic like write_ltm_npz.
//
// Errors are std::runtime_error "cannot write LTM file '<path>': ..." (a block of the wrong width,
// an invalid block, rows beyond `rows`, commit before all rows came, the spill files' I/O).
class LtmFileStream {
public:
    // The folder of `path` must exist; nothing is written to `path` before commit().
    LtmFileStream(const std::string& path, std::int64_t rows, std::int64_t cols, const NpzWriteOptions& options = {});
    ~LtmFileStream();
    LtmFileStream(const LtmFileStream&) = delete;
    LtmFileStream& operator=(const LtmFileStream&) = delete;

    // Appends the next block.rows rows (block.cols must be cols; the block must be valid).
    void append(const CsrMatrix& block);
    std::int64_t rows_written() const { return static_cast<std::int64_t>(indptr_.size()) - 1; }
    std::size_t nnz() const { return static_cast<std::size_t>(indptr_.back()); }
    // Writes the archive (all `rows` rows must have been appended) and closes the spill files;
    // with a `group`, the archive is committed into it (io/AtomicFile.h), in place at its commit.
    void commit(io::CommitGroup* group = nullptr);

private:
    [[noreturn]] void fail(const std::string& why) const;
    std::string path_;
    std::int64_t rows_ = 0, cols_ = 0;
    NpzWriteOptions options_;
    std::vector<std::int64_t> indptr_{0};
    int indices_fd_ = -1, data_fd_ = -1;
};
CsrMatrix read_ltm_npz(const std::string& path);

}  // namespace ltm
