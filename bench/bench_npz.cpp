// Writing ltm.npz (io/LtmFile.h) at zlib levels 1, 6 and 9 (and 0, stored, for reference): the
// file's size and the write time, median of --reps runs, for a real T. The figures behind the
// default level chosen in io/LtmFile.h.
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
    for (int level : {0, 1, 6, 9}) {
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
}
