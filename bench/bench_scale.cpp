// Scaling benchmark (issue "speed", point 7): time and memory of render() against paths and
// nonzeros, up to the paper scene with a 1000 x 1000 camera, a 2000 x 2000 display and 16 samples
// per pixel (16 M paths), refined representation.
//
// Each row is one render in this process. Its peak RSS is the row's own (io/PeakRss.h: the
// high-water mark is reset before the render and read after it), not the process-wide, monotone
// getrusage figure; "growth" is that peak minus the RSS when the render began (the tracer, the
// mesh and Embree's BVH are built before it), i.e. what the render itself needed at its worst
// (malloc_trim first, so that pages kept from earlier rows do not hide part of it).
// The claims the table tests, with the fits it prints:
//   memory proportional to the nonzeros: growth = a nnz through the origin (least squares), and
//     the spread of growth / nnz over the rows; T's own arrays are 8 bytes per nonzero (int32
//     column, float32 value) plus 8 per row, so a close to 8 means no overhead beyond T;
//   time linear in the paths: seconds = c paths through the origin, and the spread of seconds per
//     million paths over the rows.
// Then (not --quick) the largest render again with a small memory budget, streaming its rows to
// ltm.npz (io::LtmFileStream, spill files in --out), to show that T is then never whole in memory:
// its growth stays near the budget while T itself is far larger.
//
// Usage: bench_scale [--threads N] [--reps R] [--out DIR] [--quick]
//   --quick: the smaller rows only (under ~20 s on 2 threads); --reps R (default 1): seconds are
//   the median of R renders of each row, taken round the rows (the streamed one runs once); CSV:
//   DIR/scaling.csv.
#include <malloc.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "bench/BenchSupport.h"
#include "io/LtmFile.h"
#include "io/PeakRss.h"
#include "scene/SceneLoader.h"
#include "scene/SceneSolid.h"
#include "trace/Render.h"

using namespace ltm;

namespace {

constexpr int kDisplay = 2000;  // display pixels per side (0.05 mm over 100 mm)

struct Row {
    int n = 0, spp = 0;
    double paths = 0, seconds = 0, nnz = 0, matrix_bytes = 0, peak = 0, growth = 0;
    bool streamed = false;
};

// The rows of a streamed render, appended to an ltm.npz stream.
struct FileSink : RowSink {
    LtmFileStream& file;
    explicit FileSink(LtmFileStream& f) : file(f) {}
    void rows(std::int64_t, const CsrMatrix& block) override { file.append(block); }
};

// Least squares through the origin: the c minimising sum (y - c x)^2, c = sum xy / sum x^2.
double slope(const std::vector<Row>& rows, double Row::*x, double Row::*y) {
    double xy = 0, xx = 0;
    for (const Row& r : rows) {
        xy += r.*x * r.*y;
        xx += r.*x * r.*x;
    }
    return xy / xx;
}

}  // namespace

int main(int argc, char** argv) {
    bench::Args defaults;
    defaults.reps = 1;  // --reps R: each row rendered R times, seconds their median
    const bench::Args args = bench::parse_args(argc, argv, defaults);
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(args.threads));
    const std::vector<std::pair<int, int>> configs =
        args.quick ? std::vector<std::pair<int, int>>{{100, 16}, {250, 16}, {500, 4}, {500, 16}, {600, 8}}
                   : std::vector<std::pair<int, int>>{{100, 16}, {250, 16}, {500, 4}, {500, 16}, {700, 16},
                                                      {1000, 4}, {1000, 8}, {1000, 16}};

    // The solid does not depend on the camera: built once (the paper scene's lens and bubbles).
    Scene base = parse_scene(bench::paper_scene(configs.front().first, configs.front().second, 1e-3, kDisplay), "bench");
    const Solid solid = build_solid(base);  // with its mesh: the refined representation traces it

    const io::PeakRssMeter probe;
    std::printf("scaling: paper scene, %d x %d display, refined, %d threads; peak RSS per run by %s\n", kDisplay,
                kDisplay, args.threads, probe.method().c_str());
    if (!probe.per_run())
        std::printf("WARNING: the peak RSS column is process-wide and monotone here (upper bounds, not per run)\n");
    std::printf("%6s %4s %10s %8s %10s %9s %9s %9s %9s %8s %9s\n", "camera", "spp", "Mpaths", "seconds", "Mnnz", "T MB",
                "peak MB", "growth MB", "B/nnz", "growth/T", "s/Mpath");

    std::ofstream csv(args.out + "/scaling.csv");
    csv << "camera_pixels_per_side,samples_per_pixel,display_pixels_per_side,paths,render_seconds,nnz,matrix_bytes,"
           "peak_rss_bytes,rss_growth_bytes,bytes_per_nnz,growth_over_matrix_bytes,seconds_per_mpath,streamed,max_matrix_bytes\n";
    const auto print = [&](const Row& r, std::size_t budget) {
        std::printf("%6d %4d %10.3f %8.3f %10.3f %9.1f %9.1f %9.1f %9.2f %8.3f %9.3f%s\n", r.n, r.spp, r.paths / 1e6,
                    r.seconds, r.nnz / 1e6, r.matrix_bytes / 1e6, r.peak / 1e6, r.growth / 1e6, r.growth / r.nnz,
                    r.growth / r.matrix_bytes, r.seconds / (r.paths / 1e6), r.streamed ? "  (streamed)" : "");
        csv << r.n << "," << r.spp << "," << kDisplay << "," << r.paths << "," << r.seconds << "," << r.nnz << ","
            << r.matrix_bytes << "," << r.peak << "," << r.growth << "," << r.growth / r.nnz << ","
            << r.growth / r.matrix_bytes << "," << r.seconds / (r.paths / 1e6) << "," << (r.streamed ? 1 : 0) << "," << budget << "\n";
    };

    // One render of an n x n camera at spp, its own peak measured; with a sink, streamed above
    // `budget` bytes.
    const auto run = [&](int n, int spp, RowSink* sink, std::size_t budget) {
        Scene scene = parse_scene(bench::paper_scene(n, spp, 1e-3, kDisplay), "bench");
        const Tracer tracer(scene, solid);
        RenderOptions ro;
        ro.threads = args.threads;
        ro.row_sink = sink;
        ro.max_matrix_bytes = budget;
        // Return the heap pages the rows before freed but glibc kept (small blocks, or blocks under
        // its dynamic mmap threshold): otherwise this render reuses them unseen and its growth
        // reads low. Then reset the peak, after the tracer: the render's own memory.
        ::malloc_trim(0);
        const io::PeakRssMeter meter;
        const RenderResult r = render(tracer, ro);
        const std::uint64_t peak = meter.peak_bytes(), growth = meter.growth_bytes();
        Row row;
        row.n = n;
        row.spp = spp;
        row.paths = static_cast<double>(r.stats.paths);
        row.seconds = r.seconds;
        row.nnz = static_cast<double>(r.nnz);
        row.matrix_bytes = 8.0 * row.nnz + 8.0 * (static_cast<double>(n) * n + 1);
        row.peak = static_cast<double>(peak);
        row.growth = static_cast<double>(growth);
        row.streamed = r.streamed;
        return row;
    };

    // Repetitions go round the rows (row 1, 2, ..., then again), so that a change in the machine's
    // load during the run hits every row alike; a row's seconds are the median of its renders, its
    // memory that of the first (the renders are identical).
    std::vector<Row> rows(configs.size());
    std::vector<std::vector<double>> times(configs.size());
    for (int rep = 0; rep < std::max(1, args.reps); ++rep)
        for (size_t i = 0; i < configs.size(); ++i) {
            const Row row = run(configs[i].first, configs[i].second, nullptr, 0);
            if (rep == 0) rows[i] = row;
            times[i].push_back(row.seconds);
        }
    for (size_t i = 0; i < configs.size(); ++i) {
        rows[i].seconds = bench::median(times[i]);
        print(rows[i], 0);
    }

    const double a = slope(rows, &Row::nnz, &Row::growth), c = slope(rows, &Row::paths, &Row::seconds);
    double bmin = 1e300, bmax = 0, tmin = 1e300, tmax = 0;
    for (const Row& r : rows) {
        bmin = std::min(bmin, r.growth / r.nnz);
        bmax = std::max(bmax, r.growth / r.nnz);
        tmin = std::min(tmin, r.seconds / (r.paths / 1e6));
        tmax = std::max(tmax, r.seconds / (r.paths / 1e6));
    }
    // And with an intercept: growth = a1 nnz + b1, the fixed part (a wave's buffers, the chunk
    // being filled) apart from the proportional one.
    double sn = 0, sg = 0, snn = 0, sng = 0;
    for (const Row& r : rows) {
        sn += r.nnz;
        sg += r.growth;
        snn += r.nnz * r.nnz;
        sng += r.nnz * r.growth;
    }
    const double m = static_cast<double>(rows.size());
    const double a1 = (m * sng - sn * sg) / (m * snn - sn * sn), b1 = (sg - a1 * sn) / m;
    std::printf("\nmemory ~ nnz: growth = %.2f bytes x nnz (least squares through 0); = %.2f bytes x nnz + %.2f MB (with "
                "an intercept); T's arrays: 8 per nonzero + 8 per row; per row %.2f .. %.2f bytes/nnz\n",
                a, a1, b1 / 1e6, bmin, bmax);
    std::printf("time ~ paths: seconds = %.3f s x Mpaths (least squares through 0); per row %.3f .. %.3f s/Mpath\n", c * 1e6,
                tmin, tmax);

    if (!args.quick) {
        // The largest render again, streamed to ltm.npz under a budget of 1/8 of its T.
        const Row& big = rows.back();
        const auto budget = static_cast<std::size_t>(big.matrix_bytes / 8);
        const std::string path = args.out + "/scaling-streamed-ltm.npz";
        LtmFileStream file(path, static_cast<std::int64_t>(big.n) * big.n, static_cast<std::int64_t>(kDisplay) * kDisplay);
        FileSink sink(file);
        Row s = run(big.n, big.spp, &sink, budget);
        const double t0 = bench::now();
        file.commit();
        const double write_s = bench::now() - t0;
        std::printf("\nstreamed under a budget of %.1f MB for T (then ltm.npz written from the spill files in %.2f s, %.1f MB):\n",
                    budget / 1e6, write_s, static_cast<double>(std::filesystem::file_size(path)) / 1e6);
        print(s, budget);
        std::filesystem::remove(path);
    }
    return 0;
}
