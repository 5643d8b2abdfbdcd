#pragma once
// What the benchmark programs share: medians, a clock, and the bare-Embree baseline every speed
// is reported against (the same segments cast as plain rtcIntersect1 calls on the same triangles).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "trace/Tracer.h"

namespace ltm::bench {

// The options every benchmark program takes: --threads N --reps R --out DIR --quick --samples S
// (--ltm PATH: bench_npz's input). --help prints them; anything else, or a missing or non-positive
// number, exits with status 2 naming the argument, before any work: a mistyped flag must not run a
// long benchmark with its defaults, or write its CSV files into the current folder.
struct Args {
    int threads = 2, reps = 3;
    std::string out = ".";
    bool quick = false;
    long samples = 16;
    std::string ltm;
};

inline Args parse_args(int argc, char** argv, Args a = {}) {
    const auto usage = [&](std::FILE* to) {
        std::fprintf(to, "usage: %s [--quick] [--threads N] [--reps N] [--samples N] [--out DIR] [--ltm PATH]\n",
                     argv[0]);
    };
    const auto fail = [&](const char* what, const char* arg) {
        std::fprintf(stderr, "%s: %s: %s\n", argv[0], what, arg);
        usage(stderr);
        std::exit(2);
    };
    const auto value = [&](int& i) -> const char* {
        if (i + 1 >= argc) fail("missing value for", argv[i]);
        return argv[++i];
    };
    const auto positive = [&](int& i) -> long {
        const char* text = value(i);
        char* end = nullptr;
        const long v = std::strtol(text, &end, 10);
        if (end == text || *end != '\0' || v <= 0 || v > 1000000000L) fail("not a positive integer", text);
        return v;
    };
    for (int i = 1; i < argc; ++i) {
        const char* arg = argv[i];
        if (!std::strcmp(arg, "--help") || !std::strcmp(arg, "-h")) {
            usage(stdout);
            std::exit(0);
        } else if (!std::strcmp(arg, "--threads")) a.threads = static_cast<int>(positive(i));
        else if (!std::strcmp(arg, "--reps")) a.reps = static_cast<int>(positive(i));
        else if (!std::strcmp(arg, "--samples")) a.samples = positive(i);
        else if (!std::strcmp(arg, "--out")) a.out = value(i);
        else if (!std::strcmp(arg, "--ltm")) a.ltm = value(i);
        else if (!std::strcmp(arg, "--quick")) a.quick = true;
        else fail("unknown argument", arg);
    }
    return a;
}

// The paper scene (bench_trace, bench_estimator): the paper's lens with three bubbles of 0.1 mm
// radius, an n x n camera at spp samples per pixel, display x display pixels (500 x 500 unless
// given; bench_scale uses 2000 x 2000) over the same 100 x 100 mm, chord tolerance `chord` mm.
inline std::string paper_scene(int n, int spp, double chord = 1e-3, int display = 500) {
    char buf[1024];
    std::snprintf(buf, sizeof buf, R"(
object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
defects:
  - {type: bubble, center: [0.0, 0.0, 0.0], radius: 0.0997}
  - {type: bubble, center: [4.0, 0.0, 0.0], radius: 0.0997}
  - {type: bubble, center: [8.0, 0.0, 0.0], radius: 0.0997}
camera: {resolution: [%d, %d], size: [25.0, 25.0], numerical_aperture: 0.01, samples_per_pixel: %d}
display: {resolution: [%d, %d], size: [100.0, 100.0], z: 60.0}
mesh: {chord_tolerance: %g}
seed: 1
)",
                  n, n, spp, display, display, chord);
    return buf;
}

inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

inline double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// The segments (origin, direction) of the principal paths of every camera sample of `t`, pixel by
// pixel in the render's order: the very segments the render's paths consist of (up to the Fresnel
// branches a path takes, which the principal path does not: it transmits at every interface).
// Every pixel counts: the image's edge rows miss the lens (1.5 segments a path in the first 400
// pixels of the paper scene, 2.6 over the image), and a baseline of those alone would be a
// faster Embree than the one the render meets. Recorded in parallel, concatenated in order.
inline std::vector<std::pair<Vec3, Vec3>> record_segments(const Tracer& t) {
    const auto& cam = t.camera();
    const long pixels = cam.pixels();
    std::vector<std::vector<std::pair<Vec3, Vec3>>> rows(static_cast<size_t>(pixels));
    tbb::parallel_for(tbb::blocked_range<long>(0, pixels, 64), [&](const auto& range) {
        for (long k = range.begin(); k != range.end(); ++k) {
            auto& segs = rows[static_cast<size_t>(k)];
            const auto perm = cam.permutation(k, t.scene().seed);
            for (int s = 0; s < cam.samples_per_pixel(); ++s) {
                Rng rng(t.scene().seed, static_cast<std::uint64_t>(k), static_cast<std::uint64_t>(s));
                Vec3 o, d;
                cam.sample(k, s, perm, rng, o, d);
                const PrincipalPath p = t.principal_path(o, d);
                segs.push_back({o, d});
                for (size_t i = 0; i + 1 < p.vertices.size(); ++i)
                    segs.push_back({p.vertices[i], normalize(p.vertices[i + 1] - p.vertices[i])});
                if (!p.vertices.empty()) segs.push_back({p.vertices.back(), p.direction});
            }
        }
    });
    std::vector<std::pair<Vec3, Vec3>> all;
    size_t n = 0;
    for (const auto& r : rows) n += r.size();
    all.reserve(n);
    for (auto& r : rows) {
        all.insert(all.end(), r.begin(), r.end());
        std::vector<std::pair<Vec3, Vec3>>().swap(r);
    }
    return all;
}

// Seconds for `count` bare rtcIntersect1 calls (the recorded segments, replayed cyclically) on
// `mesh_only`'s Embree scene, on `threads` threads; median of `reps`.
inline double bare_embree_seconds(const Tracer& mesh_only, const std::vector<std::pair<Vec3, Vec3>>& segs,
                                  std::uint64_t count, int threads, int reps) {
    std::vector<double> times;
    tbb::task_arena arena(threads);
    for (int i = 0; i < reps; ++i) {
        const double t0 = now();
        std::atomic<long> sink{0};
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, count, 4096), [&](const auto& range) {
                long hits = 0;
                for (std::uint64_t j = range.begin(); j != range.end(); ++j) {
                    const auto& sg = segs[j % segs.size()];
                    hits += mesh_only.embree().raw_intersect(sg.first, sg.second, 0.0f) >= 0;
                }
                sink += hits;  // keeps the calls alive
            });
        });
        times.push_back(now() - t0);
    }
    return median(times);
}

}  // namespace ltm::bench
