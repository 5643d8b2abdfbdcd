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
// seed whatever the number of threads.
//
// Memory. Pixels are traced in waves of consecutive blocks; after each wave its rows are appended,
// in row order, to T's arrays, which grow in fixed chunks of their own mappings and are copied
// once into RenderResult::T at the end, each copied stretch's pages released right behind the
// copy. So the peak is T's own size (8 bytes per nonzero, 8 per row) plus one wave's rows and a
// few MiB: no per-row containers, no doubling vectors, no second copy of T.
// With a row sink and a budget (RenderOptions::row_sink, max_matrix_bytes), T exceeds the budget
// in memory by at most one wave: once what it holds does, the render hands its rows to the sink
// block by block, in row order, and from then on keeps only the current wave (streaming; e.g.
// ltm.npz written from the blocks).
//
// Threads: render() keeps no process-wide thread state. With options.threads = n > 0 it runs in a
// task arena of its own with n threads; with 0 it runs in the caller's arena (all cores when the
// caller is in none), so several renders can share one arena concurrently (the dataset command
// renders several samples at once this way).
#include <algorithm>
#include <cstddef>
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

// Receives T's rows in row order when a render streams (RenderOptions::row_sink).
class RowSink {
public:
    virtual ~RowSink() = default;
    // Rows [first_row, first_row + block.rows) of T: `block` is a valid CSR matrix with T's
    // columns. Blocks arrive in order and cover every row exactly once; a block may have any
    // number of rows (whole waves of pixel blocks, not camera image rows).
    virtual void rows(std::int64_t first_row, const CsrMatrix& block) = 0;
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
    // Streaming (with `row_sink`, for a full render without a pattern or pixel subset): once T's
    // arrays held in memory (8 bytes per nonzero + 8 per row) would exceed max_matrix_bytes, the
    // rows rendered so far and every later block go to row_sink instead; RenderResult::T is then
    // empty and `streamed` set. 0, or no sink: T is always kept whole. The rows the sink receives
    // are bit-identical to T's.
    RowSink* row_sink = nullptr;
    std::size_t max_matrix_bytes = 0;
};

struct RenderResult {
    CsrMatrix T;                         // without a pattern, unless streamed
    bool streamed = false;               // T's rows went to RenderOptions::row_sink
    std::size_t nnz = 0;                 // T's nonzeros (streamed or not)
    std::vector<double> image;           // with a pattern: y per camera pixel ...
    std::vector<double> image_stderr;    // ... and its Monte Carlo standard error
    // track_defects: how many of each pixel's samples met each defect first, for the pairs with at
    // least one (sorted by pixel, then defect); memory grows with the defects' images only.
    bool tracked_defects = false;
    std::vector<DefectPaths> defect_paths;
    PathStats stats;
    double seconds = 0;        // the whole render: trace_seconds + merge_seconds
    double trace_seconds = 0;  // tracing, merging each row's samples, holding the rows wave by wave
    double merge_seconds = 0;  // moving the held rows into the CSR matrix (or the last to the sink)
};

// One path branch's contribution to a row, before the row is merged.
struct RowEntry {
    std::int32_t column;
    double weight;
};
// Appends the merged row to `columns` and `values`: one entry per distinct column of `entries`,
// the weights summed in the order they come (sample order, so the sum, and the float it rounds
// to, does not depend on threads) and divided by the samples per pixel. Returns the row's length.
std::int32_t merge_row(std::vector<RowEntry>& entries, int spp, std::vector<std::int32_t>& columns,
                       std::vector<float>& values);

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
// Sixteen samples at a time: their streams are seeded and drawn from in SIMD lanes.
template <class F>
void for_each_camera_sample(const TelecentricCamera& cam, std::uint64_t seed, long k, F&& f) {
    const std::vector<int> perm = cam.permutation(k, seed);
    constexpr int kChunk = 16;  // TelecentricCamera::sample_packet's most
    Rng rng[kChunk];
    Vec3 o[kChunk], d[kChunk];
    for (int s0 = 0; s0 < cam.samples_per_pixel(); s0 += kChunk) {
        const int n = std::min(kChunk, cam.samples_per_pixel() - s0);
        cam.sample_packet(k, s0, n, perm, seed, rng, o, d);
        for (int i = 0; i < n; ++i) f(s0 + i, rng[i], o[i], d[i]);
    }
}

}  // namespace ltm
