// Tracing benchmarks. Medians of repeated runs in one process, on this machine:
//   a. the paper scene (100 x 100 camera, 500 x 500 display, r1 = 50, r2 = -50, t = 6, D = 25 mm,
//      three bubbles) at 256 samples per pixel: paths/s and ray segments/s, per representation;
//   b. after each render of a, as many ray segments cast as bare rtcIntersect1 calls on the same
//      triangle mesh (the segments of real paths, recorded, then replayed), same threads:
//      efficiency a/b, render by render;
//   c. display-hit error against the analytic reference and render time over tessellation levels,
//      with and without refinement, and for the analytic primitives (CSV: error_vs_time.csv);
// (Time and memory against resolution and samples per pixel: bench_scale.cpp.)
// Usage: bench_trace [--threads N] [--reps R] [--out DIR] [--quick]
//   --quick: a and b only, at 64 spp, ending with the ratio table and where the time goes
//   (scripts/bench --quick).
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "bench/BenchSupport.h"
#include "bench/StageBreakdown.h"
#include "scene/SceneLoader.h"
#include "trace/Render.h"
#include "validation/AnalyticScene.h"
#include "validation/ValidationRays.h"

using namespace ltm;
using bench::median;
using bench::now;
using bench::paper_scene;
using bench::record_segments;

namespace {

struct Setup {
    Scene scene;
    Solid solid;
};
Setup setup(const std::string& yaml) {
    Setup s;
    s.scene = parse_scene(yaml, "bench");
    s.solid = build_solid(Lens(s.scene.object.lens), s.scene.defects, s.scene.mesh);
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    const bench::Args args = bench::parse_args(argc, argv);
    const int threads = args.threads, reps = args.reps;
    const std::string out = args.out;
    const bool quick = args.quick;
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
    const int spp = quick ? 64 : 256;
    std::printf("threads %d, repetitions %d (medians)\n\n", threads, reps);

    // a + b. Each render is followed by a bare replay of as many segments on the same mesh, and
    // its ratio taken to that replay: on a machine whose speed drifts between phases (a shared
    // host), a render and the replay right after it see the same machine, and the median of
    // those pairs is firmer than the ratio of two medians taken apart (shown too).
    const Setup paper = setup(paper_scene(100, spp));
    TracerOptions mo;
    mo.representation = Representation::MeshOnly;  // its Embree scene: exactly the solid's triangles
    const Tracer mesh(paper.scene, paper.solid, mo);
    const auto segs = record_segments(Tracer(paper.scene, paper.solid, TracerOptions{}));
    std::printf("a. paper scene, 100 x 100 x %d spp, %zu mesh triangles\n", spp, paper.solid.mesh.num_triangles());
    std::printf("%-10s %12s %14s %16s %12s\n", "repr", "seconds", "Mpaths/s", "Msegments/s", "seg/path");
    struct Row {
        const char* name;
        double seg_rate = 0;  // median
        double paired = 0;    // median of the renders' ratios to their replays
        const char* target;
    };
    std::vector<Row> rows;
    std::vector<double> bare_rates;
    std::uint64_t segments = 0;
    for (auto rep : {Representation::Analytic, Representation::Refined, Representation::MeshOnly}) {
        TracerOptions o;
        o.representation = rep;
        const Tracer t(paper.scene, paper.solid, o);
        std::vector<double> times, ratios;
        RenderResult r;
        for (int i = 0; i < reps; ++i) {
            RenderOptions ro;
            ro.threads = threads;
            r = render(t, ro);
            times.push_back(r.seconds);
            const double bare = bench::bare_embree_seconds(mesh, segs, r.stats.segments, threads, 1);
            bare_rates.push_back(double(r.stats.segments) / bare);
            ratios.push_back(bare / r.seconds);  // (segments / render) / (segments / bare)
        }
        const double s = median(times);
        const double seg_rate = r.stats.segments / s;
        if (rep == Representation::Refined) segments = r.stats.segments;
        rows.push_back({to_string(rep), seg_rate, median(ratios),
                        rep == Representation::Analytic ? ">= 1.0" : rep == Representation::Refined ? ">= 0.6" : ">= 1.5"});
        std::printf("%-10s %12.3f %14.3f %16.3f %12.3f\n", to_string(rep), s, r.stats.paths / s / 1e6, seg_rate / 1e6,
                    double(r.stats.segments) / r.stats.paths);
    }
    {
        const double raw_rate = median(bare_rates);
        const long paper_pixels = mesh.camera().pixels();
        std::printf("\nb. %llu bare rtcIntersect1 calls after each render (the %zu recorded segments of every pixel's "
                    "principal paths, %.3f a path) on the same %zu triangles: %.3f Mrays/s (median of %zu)\n\n",
                    static_cast<unsigned long long>(segments), segs.size(),
                    double(segs.size()) / (double(paper_pixels) * spp), paper.solid.mesh.num_triangles(), raw_rate / 1e6,
                    bare_rates.size());
        // The ratio table: each representation's segments per second over the bare rtcIntersect1
        // rate, same segments, same threads, same run, beside its target (docs/benchmarks.md).
        std::printf("ratio table: segments/s over bare rtcIntersect1, %d threads, this run\n", threads);
        std::printf("%-12s %12s %8s %10s %8s\n", "repr", "Msegments/s", "paired", "medians", "target");
        for (const Row& row : rows)
            std::printf("%-12s %12.3f %8.2f %10.2f %8s\n", row.name, row.seg_rate / 1e6, row.paired, row.seg_rate / raw_rate,
                        row.target);
        std::printf("%-12s %12.3f %8.2f %10.2f\n", "bare", raw_rate / 1e6, 1.0, 1.0);
        std::printf("(paired: the median over the renders of each one's ratio to the bare replay right after it;\n"
                    " medians: the median render's rate over the median replay's)\n\n");
    }
    {
        // Where the time goes: each stage replayed alone on one thread (bench/StageBreakdown.h).
        std::printf("where the time goes: one-thread render, %d spp, per path (bench/StageBreakdown.h)\n", spp);
        TracerOptions mo;
        mo.representation = Representation::MeshOnly;
        const Tracer mesh(paper.scene, paper.solid, mo);
        for (auto rep : {Representation::Analytic, Representation::Refined, Representation::MeshOnly}) {
            TracerOptions o;
            o.representation = rep;
            const Tracer t(paper.scene, paper.solid, o);
            bench::print_stage_breakdown(to_string(rep), bench::stage_breakdown(t, mesh, reps, out + "/stage-write"));
        }
        std::printf("\n");
    }
    if (quick) return 0;  // scripts/bench --quick: the ratio table and the breakdown only

    // c. error vs time.
    {
        std::ofstream csv(out + "/error_vs_time.csv");
        csv << "representation,chord_tolerance_mm,triangles,render_seconds,max_display_error_mm,median_display_error_mm\n";
        std::printf("c. error vs time (100 x 100 x 16 spp renders; errors over the validation rays)\n");
        std::printf("%-10s %10s %10s %10s %14s %14s\n", "repr", "chord mm", "triangles", "seconds", "max err mm", "median err mm");
        for (double chord : {1e-2, 3e-3, 1e-3, 3e-4, 1e-4}) {
            const Setup sc = setup(paper_scene(100, 16, chord));
            const validation::AnalyticScene ref(sc.scene);
            const auto rays = validation::validation_rays(sc.scene, 2);
            for (auto rep : {Representation::Refined, Representation::MeshOnly, Representation::Analytic}) {
                if (rep == Representation::Analytic && chord != 1e-3) continue;  // no mesh: one point
                TracerOptions o;
                o.representation = rep;
                const Tracer t(sc.scene, sc.solid, o);
                std::vector<double> times;
                for (int i = 0; i < reps; ++i) {
                    RenderOptions ro;
                    ro.threads = threads;
                    times.push_back(render(t, ro).seconds);
                }
                std::vector<double> errs;
                for (const auto& ray : rays) {
                    const auto a = ref.principal_path(ray.origin, ray.direction);
                    const auto b = t.principal_path(ray.origin, ray.direction);
                    if (!a.on_display || !b.display_hit) continue;
                    errs.push_back(std::hypot(a.display_x - b.x, a.display_y - b.y));
                }
                const double mx = errs.empty() ? 0 : *std::max_element(errs.begin(), errs.end());
                const double md = errs.empty() ? 0 : median(errs);
                std::printf("%-10s %10.0e %10zu %10.3f %14.3e %14.3e\n", to_string(rep), chord,
                            rep == Representation::Analytic ? size_t(0) : sc.solid.mesh.num_triangles(), median(times), mx, md);
                csv << to_string(rep) << "," << chord << "," << (rep == Representation::Analytic ? 0 : sc.solid.mesh.num_triangles())
                    << "," << median(times) << "," << mx << "," << md << "\n";
            }
        }
    }

    return 0;
}
