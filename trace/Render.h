#pragma once
// Renders the light transport matrix T (or, with a display pattern x, the camera image y = T x
// directly) by Monte Carlo path tracing.
//
// T[k, l] = (1 / S) sum over the S samples of pixel k of the weight of those paths that land on
// display pixel l: the expected fraction of the pixel's ray-of-sight throughput reaching l.
// Sample s of pixel k draws all its random numbers from the stream Rng(seed, k, s), pixels are
// processed in fixed blocks and each row sums its samples in sample order, so the result is
// bit-identical for a given seed whatever the number of threads. Memory grows with the nonzeros:
// a row holds at most one entry per sample until it is merged.
#include <cstdint>
#include <vector>

#include "trace/CsrMatrix.h"
#include "trace/Tracer.h"

namespace ltm {

struct RenderOptions {
    int threads = 0;                          // 0: all cores
    bool progress = false;                    // progress bar with paths/s and ETA on stderr
    const std::vector<float>* pattern = nullptr;  // render y = T x for this display pattern instead
    std::uint64_t seed_offset = 0;            // added to the scene's seed (independent re-renders)
};

struct RenderResult {
    CsrMatrix T;                         // without a pattern
    std::vector<double> image;           // with a pattern: y per camera pixel ...
    std::vector<double> image_stderr;    // ... and its Monte Carlo standard error
    PathStats stats;
    double seconds = 0;
};

RenderResult render(const Tracer& tracer, const RenderOptions& options);

}  // namespace ltm
