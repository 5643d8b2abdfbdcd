// Writing ltm.npz (io/LtmFile.h) at igzip levels 1, 2 and 3 (and 0, stored, for reference): the
// file's size and the write time, median of --reps runs, for a real T. The figures behind the
// default level chosen in io/LtmFile.h. For comparison, in the same run: zlib's level 1 (what
// libzip deflates entries with on its own) deflating the same arrays,
// the deflate alone (no CRC, no file), which is a lower bound of a zlib write.
//
// Usage: bench_npz --ltm PATH/ltm.npz [--reps R] [--out DIR]
//   PATH/ltm.npz is a rendered T, e.g. of a paper scene:
//     ltmsim render scenes/paper/bubbles-r1.yaml -o /tmp/zipm --overwrite --verbose
//   (its --verbose output gives the trace time to compare the write time with). The files are
//   written to DIR (default: the folder of PATH) as bench-npz-<level>.npz and removed afterwards.
// Prints one line per level: level, size in bytes and MB, ratio to the raw arrays, median seconds.
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <zlib.h>

#include "bench/BenchSupport.h"
#include "io/LtmFile.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
    ltm::bench::Args defaults;
    defaults.reps = 5;
    defaults.out.clear();
    const ltm::bench::Args args = ltm::bench::parse_args(argc, argv, defaults);
    const std::string& ltm = args.ltm;
    if (ltm.empty()) {
        std::fprintf(stderr, "usage: bench_npz --ltm PATH/ltm.npz [--reps R] [--out DIR]\n");
        return 2;
    }
    const std::string out = args.out.empty() ? fs::path(ltm).parent_path().string() : args.out;
    const ltm::CsrMatrix T = ltm::read_ltm_npz(ltm);
    const double raw = static_cast<double>(T.indices.size() * 4 + T.indptr.size() * 4 + T.data.size() * 4);
    std::printf("T: %lld x %lld, nnz %zu, raw arrays %.1f MB; %d runs per level\n", static_cast<long long>(T.rows),
                static_cast<long long>(T.cols), T.nnz(), raw / 1e6, args.reps);
    std::printf("%5s %14s %9s %7s %10s\n", "level", "bytes", "MB", "ratio", "median s");
    for (int level : {0, 1, 2, 3}) {
        ltm::NpzWriteOptions o;
        o.compression_level = level;
        const std::string path = (fs::path(out) / ("bench-npz-" + std::to_string(level) + ".npz")).string();
        std::vector<double> times;
        for (int r = 0; r < args.reps; ++r) {
            const double t0 = ltm::bench::now();
            ltm::write_ltm_npz(path, T, o);
            times.push_back(ltm::bench::now() - t0);
        }
        const double size = static_cast<double>(fs::file_size(path));
        std::printf("%5d %14.0f %9.2f %7.3f %10.3f\n", level, size, size / 1e6, size / raw, ltm::bench::median(times));
        fs::remove(path);
    }
    // zlib level 1, raw deflate of each array's bytes as the file holds them (int32 indptr here).
    std::vector<std::int32_t> indptr(T.indptr.begin(), T.indptr.end());
    const std::vector<std::pair<const void*, std::size_t>> arrays = {
        {T.indices.data(), T.indices.size() * sizeof(T.indices[0])},
        {indptr.data(), indptr.size() * 4},
        {T.data.data(), T.data.size() * sizeof(T.data[0])}};
    std::vector<double> times;
    double zsize = 0;
    std::vector<unsigned char> buf;
    for (int r = 0; r < args.reps; ++r) {
        const double t0 = ltm::bench::now();
        zsize = 0;
        for (const auto& [p, n] : arrays) {
            z_stream z{};
            deflateInit2(&z, 1, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY);
            buf.resize(deflateBound(&z, n));
            z.next_in = static_cast<Bytef*>(const_cast<void*>(p));
            z.avail_in = static_cast<uInt>(n);
            z.next_out = buf.data();
            z.avail_out = static_cast<uInt>(buf.size());
            deflate(&z, Z_FINISH);
            zsize += static_cast<double>(z.total_out);
            deflateEnd(&z);
        }
        times.push_back(ltm::bench::now() - t0);
    }
    std::printf("%5s %14.0f %9.2f %7.3f %10.3f   (zlib level 1, deflate alone)\n", "zlib", zsize, zsize / 1e6,
                zsize / raw, ltm::bench::median(times));
}
