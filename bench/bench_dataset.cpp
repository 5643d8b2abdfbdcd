// Dataset throughput: paper-scale samples (scenes/default.yaml: 100 x 100 camera,
// 500 x 500 display, 64 paths per pixel), previews off, on N threads (2 unless given):
//   enclosed   scenes/datasets/paper-enclosed.yaml: 1-4 bubbles and particles, no Boolean;
//   mixed      scenes/datasets/paper-mixed.yaml: 1-4 defects, scratches among them;
//   scratched  the mixed spec with a scratch in every sample (and none defect-free): a Boolean
//              in every sample.
// For each: samples/s of whole runs (median of R runs of S samples, samples rendered concurrently
// as `ltmsim dataset` does), and the time per stage per sample from a run with one sample at a
// time (so the stages do not share the threads). CSV: OUT/dataset.csv.
// Usage: bench_dataset [--threads N] [--reps R] [--samples S] [--out DIR]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "bench/BenchSupport.h"
#include "scene/SceneLoader.h"
#include "scene/SceneSolid.h"
#include "study/Dataset.h"
#include "study/DatasetSpec.h"
#include "trace/Render.h"

using namespace ltm;
namespace fs = std::filesystem;

namespace {

std::string read(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
    const auto at = s.find(from);
    if (at == std::string::npos) throw std::runtime_error("bench_dataset: the spec changed; cannot find: " + from);
    return s.replace(at, from.size(), to);
}

}  // namespace

int main(int argc, char** argv) {
    bench::Args defaults;
    defaults.out = "out/bench";
    const bench::Args args = bench::parse_args(argc, argv, defaults);
    const int threads = args.threads, reps = args.reps;
    const long samples = args.samples;
    const std::string out = args.out;
    const fs::path specs = fs::path(bench::source_dir()) / "scenes" / "datasets";
    const std::string mixed = read(specs / "paper-mixed.yaml");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"enclosed", read(specs / "paper-enclosed.yaml")},
        {"mixed", mixed},
        {"scratched", replaced(replaced(mixed, "    count: {uniform_int: [0, 1]}\n    surface:", "    count: 1\n    surface:"),
                               "defect_free_fraction: 0.1", "defect_free_fraction: 0")},
    };
    fs::create_directories(out);
    std::ofstream csv(fs::path(out) / "dataset.csv");
    csv << "spec,threads,samples,samples_per_s,bare_embree_ratio,stage,ms_per_sample\n";
    const fs::path work = fs::temp_directory_path() / fmt::format("ltmsim-bench-dataset-{}", ::getpid());
    // The baseline: a sample's worth of ray segments (those of the defect-free default scene) as
    // bare rtcIntersect1 calls on its triangle mesh, on the same threads.
    double bare = 0;
    {
        const Scene scene = load_scene((fs::path(bench::source_dir()) / "scenes" / "default.yaml").string());
        const Scene free = defect_free(scene);
        const Solid solid = build_solid(free, nullptr, /*surfaces_only=*/false);
        TracerOptions a, m;
        a.representation = Representation::Analytic;
        m.representation = Representation::MeshOnly;
        const Tracer analytic(free, solid, a), mesh(free, solid, m);
        RenderOptions ro;
        ro.threads = threads;
        const std::uint64_t segments = render(analytic, ro).stats.segments;
        bare = bench::bare_embree_seconds(mesh, bench::record_segments(analytic), segments, threads, reps);
        std::printf("baseline: %llu bare rtcIntersect1 calls (one sample's segments) take %.3f s on %d threads\n",
                    static_cast<unsigned long long>(segments), bare, threads);
    }
    std::printf("dataset throughput, %d threads, %ld samples per run, median of %d runs\n", threads, samples, reps);
    for (const auto& [name, text] : cases) {
        const DatasetSpec spec = parse_dataset_spec(replaced(text, "samples: 1000", fmt::format("samples: {}", samples)),
                                                    (specs / "paper-mixed.yaml").string());
        std::vector<double> rates;
        using bench::median;
        for (int r = 0; r < reps; ++r) {
            fs::remove_all(work);
            DatasetOptions o;
            o.out = work.string();
            o.threads = threads;
            o.version = "bench";
            const DatasetSummary s = run_dataset(spec, o);
            rates.push_back(static_cast<double>(s.rendered) / s.seconds);
        }
        // One sample at a time: each stage's own cost.
        fs::remove_all(work);
        DatasetOptions seq;
        seq.out = work.string();
        seq.threads = threads;
        seq.jobs = 1;
        seq.version = "bench";
        const DatasetSummary s = run_dataset(spec, seq);
        const double rate = median(rates);
        std::printf("\n%-10s %.2f samples/s (one at a time: %.2f samples/s); a sample costs %.1f x the bare-Embree "
                    "baseline; per sample, one at a time:\n",
                    name.c_str(), rate, static_cast<double>(s.rendered) / s.seconds, 1.0 / rate / bare);
        double write = 0, render = 0;
        for (const auto& stage : s.stage_order) {
            const double ms = 1e3 * s.stage_seconds.at(stage) / static_cast<double>(s.rendered);
            std::printf("  %-14s %8.1f ms\n", stage.c_str(), ms);
            csv << fmt::format("{},{},{},{},{},{},{}\n", name, threads, samples, rate, 1.0 / rate / bare, stage, ms);
            if (stage == "write") write = ms;
            if (stage == "render" || stage == "reference" || stage == "features") render += ms;
        }
        std::printf("  write / (render + reference + features) = %.2f\n", write / std::max(render, 1e-9));
    }
    fs::remove_all(work);
    return 0;
}
