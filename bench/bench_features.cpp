// Row features of a paper-scale light transport matrix (features/Features.h): 100 x 100 camera,
// 500 x 500 display of 100 x 100 mm, i.e. T with 10^4 rows and 2.5 x 10^5 columns, built
// synthetically and deterministically to look like a render of a lens:
//  - every camera pixel sees a cluster of 30 display pixels (out of a 9 x 9 window, Gaussian-ish
//    values) around a centre that moves smoothly and non-linearly across the camera (a lens
//    mapping the camera onto the display with some distortion);
//  - every 100th camera pixel (a defect) adds 200 display pixels scattered over the whole display;
// about 3.2 x 10^5 nonzeros. All features, with a reference mean (so the Deflection channels too).
// BM_Previews writes every channel's preview PNG (features/Plot.h), one after another on one
// thread, into a temporary folder: what a render's write stage spends per preview; tile 10
// repeats each channel 10 x 10 times, a 1000 x 1000 preview as the industrial scene's.
// Usage: bench_features --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// (the median of the 5 repetitions is the figure to quote; "threads" is the TBB limit).
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "features/Features.h"
#include "features/Plot.h"
#include "io/AtomicFile.h"
#include "io/Image.h"
#include "io/LtmFile.h"

using namespace ltm;

namespace {

constexpr int kN = 100, kM = 100, kQ = 500, kP = 500;
constexpr double kWidth = 100.0, kHeight = 100.0;

// splitmix64: a fixed, portable hash, so the matrix is the same everywhere.
std::uint64_t mix(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}
double unit(std::uint64_t h) { return static_cast<double>(h >> 11) * 0x1p-53; }

struct Synthetic {
    CsrMatrix T;
    std::vector<float> reference;  // the cluster centres in mm: the "defect-free" means
};

const Synthetic& synthetic() {
    static const Synthetic s = [] {
        Synthetic s;
        s.T = CsrMatrix::zeros(kN * kM, static_cast<std::int64_t>(kP) * kQ);
        std::vector<std::pair<std::int32_t, float>> row;
        std::vector<std::pair<std::uint64_t, int>> window;
        for (int m = 0; m < kM; ++m)
            for (int n = 0; n < kN; ++n) {
                const int k = m * kN + n;
                const double u = (n + 0.5) / kN - 0.5, v = (m + 0.5) / kM - 0.5, r2 = u * u + v * v;
                const double qc = 250 + 380 * u * (1 - 0.5 * r2), pc = 250 + 380 * v * (1 - 0.5 * r2);
                s.reference.push_back(static_cast<float>(-kWidth / 2 + (qc + 0.5) * kWidth / kQ));
                s.reference.push_back(static_cast<float>(kHeight / 2 - (pc + 0.5) * kHeight / kP));
                const int p0 = static_cast<int>(std::lround(pc)), q0 = static_cast<int>(std::lround(qc));
                // 30 of the 81 pixels of the window, chosen by hash.
                window.clear();
                for (int i = 0; i < 81; ++i) window.push_back({mix(static_cast<std::uint64_t>(k) * 81 + i), i});
                std::partial_sort(window.begin(), window.begin() + 30, window.end());
                row.clear();
                for (int j = 0; j < 30; ++j) {
                    const int dp = window[j].second / 9 - 4, dq = window[j].second % 9 - 4;
                    const double g = std::exp(-(dp * dp + dq * dq) / 8.0) * (0.5 + 0.5 * unit(window[j].first));
                    row.push_back({(p0 + dp) * kQ + (q0 + dq), static_cast<float>(g / 30)});
                }
                if (k % 100 == 37)
                    for (int j = 0; j < 200; ++j) {
                        const std::uint64_t h = mix(0xD1B54A32D192ED03ull ^ (static_cast<std::uint64_t>(k) * 200 + j));
                        row.push_back({static_cast<std::int32_t>(h % (kP * kQ)), static_cast<float>(1e-4 * unit(mix(h)))});
                    }
                std::sort(row.begin(), row.end());
                row.erase(std::unique(row.begin(), row.end(),
                                      [](const auto& a, const auto& b) { return a.first == b.first; }),
                          row.end());
                for (const auto& [l, val] : row) {
                    s.T.indices.push_back(l);
                    s.T.data.push_back(val);
                }
                s.T.indptr[static_cast<std::size_t>(k) + 1] = static_cast<std::int64_t>(s.T.data.size());
            }
        return s;
    }();
    return s;
}

void BM_AllFeatures(benchmark::State& state) {
    const Synthetic& s = synthetic();
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(0)));
    const DisplayGrid display{kQ, kP, kWidth, kHeight};
    const FeatureOptions options;  // threshold 0, energy fraction 0.99, dark block 60
    for (auto _ : state) {
        FeatureImages f = compute_features(s.T, kN, kM, display, options, &s.reference);
        benchmark::DoNotOptimize(f.channels.data());
        benchmark::ClobberMemory();
    }
    state.counters["nnz"] = static_cast<double>(s.T.nnz());
    state.counters["rows_per_s"] =
        benchmark::Counter(static_cast<double>(s.T.rows), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_AllFeatures)->ArgName("threads")->Arg(2)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Previews(benchmark::State& state) {
    const Synthetic& s = synthetic();
    const DisplayGrid display{kQ, kP, kWidth, kHeight};
    const FeatureImages f = compute_features(s.T, kN, kM, display, FeatureOptions{}, &s.reference);
    // tile: every channel repeated tile x tile times (10: 1000 x 1000, the industrial scene's).
    const int tile = static_cast<int>(state.range(0)), w = kN * tile, h = kM * tile;
    std::vector<std::pair<std::string, std::vector<float>>> channels;
    for (const auto& [name, values] : f.channels) {
        std::vector<float> v(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
        for (int m = 0; m < h; ++m)
            for (int n = 0; n < w; ++n)
                v[static_cast<std::size_t>(m) * static_cast<std::size_t>(w) + static_cast<std::size_t>(n)] =
                    values[static_cast<std::size_t>(m % kM) * kN + static_cast<std::size_t>(n % kN)];
        channels.emplace_back(name, std::move(v));
    }
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("ltm-bench-previews-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const int scale = std::max(1, 400 / w);  // as a render's write stage (app/FeatureOutputs.cpp)
    for (auto _ : state)
        for (const auto& [name, values] : channels)
            write_pseudo_colour_png((dir / (name + ".png")).string(), values, w, h, feature_title(name), NAN, NAN,
                                    scale, ImageExtent{kWidth, kHeight});
    fs::remove_all(dir);
    state.counters["previews"] = static_cast<double>(channels.size());
    // seconds per preview, printed with an SI prefix (m: milliseconds)
    state.counters["s_per_preview"] = benchmark::Counter(
        static_cast<double>(channels.size()), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Previews)->ArgName("tile")->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond)->UseRealTime();

// BM_WriteFile writes one of a render's files from the synthetic T and its features, on one
// thread, made durable as a render's are (io::CommitGroup): 0 features.exr, 1 features.npz,
// 2 ltm.npz, 3 reference.exr (the means of every pixel), 4 one preview (BrightField). The CPU time
// is the file's own work; the real time adds the fsync.
void BM_WriteFile(benchmark::State& state) {
    const Synthetic& s = synthetic();
    const DisplayGrid display{kQ, kP, kWidth, kHeight};
    const FeatureImages f = compute_features(s.T, kN, kM, display, FeatureOptions{}, &s.reference);
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("ltm-bench-files-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const int kind = static_cast<int>(state.range(0));
    for (auto _ : state) {
        io::CommitGroup group;
        switch (kind) {
            case 0: write_exr((dir / "features.exr").string(), kN, kM, f.channels, &group); break;
            case 1: write_npz_channels((dir / "features.npz").string(), kN, kM, f.channels, &group); break;
            case 2: {
                NpzWriteOptions o;
                o.group = &group;
                write_ltm_npz((dir / "ltm.npz").string(), s.T, o);
                break;
            }
            case 3:
                write_exr((dir / "reference.exr").string(), kN, kM,
                          {{"MeanX", s.reference.data(), s.reference.size() / 2, 2},
                           {"MeanY", s.reference.data() + 1, s.reference.size() / 2, 2}},
                          &group);
                break;
            default:
                write_pseudo_colour_png((dir / "BrightField.png").string(), f.channels[0].second, kN, kM,
                                        feature_title(f.channels[0].first), NAN, NAN, 400 / kN,
                                        ImageExtent{kWidth, kHeight}, &group);
        }
        group.commit();
    }
    fs::remove_all(dir);
}
BENCHMARK(BM_WriteFile)->ArgName("file")->DenseRange(0, 4)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
