#pragma once
// Renders the light transport matrix T (or, with a display pattern x, the camera image y = T x
// directly) by Monte Carlo path tracing.
//
// T[k, l] = (1 / S) sum over the S samples of pixel k of the weight of those paths that land on
// display pixel l: the expected fraction of the pixel's ray-of-sight throughput reaching l. A
// sample is one path with the sample estimator, or the branches it splits into with the split
// estimator (scene.tracing; Tracer::sample_paths), each landing where it lands with its weight.
// Sample s of pixel k draws all its random numbers from the stream Rng(seed, k, s) (all its
// branches, in their fixed order), pixels are processed in fixed blocks and each row sums its
// samples in sample order (branches in branch order), so the result is bit-identical for a given
// seed whatever the number of threads. Memory grows with the nonzeros: a row holds at most one
// entry per branch until it is merged.
//
// Threads: render() keeps no process-wide thread state. With options.threads = n > 0 it runs in a
// task arena of its own with n threads; with 0 it runs in the caller's arena (all cores when the
// caller is in none), so several renders can share one arena concurrently (the dataset command
// renders several samples at once this way).
#include <cstdint>
#include <utility>
#include <vector>

#include "io/CsrMatrix.h"
#include "trace/Tracer.h"

namespace ltm {

struct DefectPaths {
    std::int32_t pixel;   // camera pixel k
    std::int32_t defect;  // index into the scene's defects
    std::uint32_t paths;  // samples of pixel k whose path met this defect first
};

struct RenderOptions {
    int threads = 0;                          // 0: the caller's task arena; n > 0: an arena of n threads
    bool progress = false;                    // progress bar with paths/s and ETA on stderr
    const std::vector<float>* pattern = nullptr;  // render y = T x for this display pattern instead
    // 0: the scene's own seed. Otherwise the render uses mix_seed(scene.seed, stream) (Rng.h): an
    // independent re-render of the same scene.
    std::uint64_t stream = 0;
    // Only these camera pixels (ascending, each once); the rows (image values) of the others stay
    // empty (zero). Each rendered pixel gets exactly the values a full render gives it.
    const std::vector<long>* pixels = nullptr;
    // Count, per camera pixel and defect, the samples whose path met the defect first
    // (PathResult::defect): the ground truth of where each defect is seen (study/GroundTruth.h).
    bool track_defects = false;
};

struct RenderResult {
    CsrMatrix T;                         // without a pattern
    std::vector<double> image;           // with a pattern: y per camera pixel ...
    std::vector<double> image_stderr;    // ... and its Monte Carlo standard error
    // track_defects: how many of each pixel's samples met each defect first, for the pairs with at
    // least one (sorted by pixel, then defect); memory grows with the defects' images only.
    bool tracked_defects = false;
    std::vector<DefectPaths> defect_paths;
    PathStats stats;
    double seconds = 0;        // the whole render: trace_seconds + merge_seconds
    double trace_seconds = 0;  // tracing the paths and merging each row's samples (in parallel)
    double merge_seconds = 0;  // assembling the rows into the CSR matrix (serial)
};

// One path branch's contribution to a row, before the row is merged.
struct RowEntry {
    std::int32_t column;
    double weight;
};
// Appends the merged row to `row`: one entry per distinct column of `entries`, the weights summed
// in the order they come (a stable sort by column keeps sample order, so the sum, and the float
// it rounds to, does not depend on threads) and divided by the samples per pixel. Reorders
// `entries`.
void merge_row(std::vector<RowEntry>& entries, int spp, std::vector<std::pair<std::int32_t, float>>& row);

RenderResult render(const Tracer& tracer, const RenderOptions& options);

// defect_paths as a dense pixels x defects table: [k * defects + j].
inline std::vector<std::uint32_t> dense_defect_paths(const RenderResult& r, long pixels, int defects) {
    std::vector<std::uint32_t> out(static_cast<size_t>(pixels) * static_cast<size_t>(defects), 0);
    for (const DefectPaths& e : r.defect_paths)
        out[static_cast<size_t>(e.pixel) * static_cast<size_t>(defects) + static_cast<size_t>(e.defect)] = e.paths;
    return out;
}

// The seed a render with these options uses (scene.seed, or mixed with options.stream).
std::uint64_t render_seed(const Scene& scene, const RenderOptions& options);

// The camera samples of pixel k exactly as render() draws them with `seed`: for s = 0 .. spp - 1,
// f(s, rng, origin, direction) with rng = Rng(seed, k, s) just after the camera took the ray from
// it, where the path's own draws begin (so a caller can trace the render's very paths again).
template <class F>
void for_each_camera_sample(const TelecentricCamera& cam, std::uint64_t seed, long k, F&& f) {
    const std::vector<int> perm = cam.permutation(k, seed);
    for (int s = 0; s < cam.samples_per_pixel(); ++s) {
        Rng rng(seed, static_cast<std::uint64_t>(k), static_cast<std::uint64_t>(s));
        Vec3 o, d;
        cam.sample(k, s, perm, rng, o, d);
        f(s, rng, o, d);
    }
}

}  // namespace ltm
