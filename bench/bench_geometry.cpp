// Geometry benchmarks: scene set-up of a defect-free lens (parse + mesh), and the
// paper's lens with three bubbles and one scratch at the default tessellation.
//   build/bench/bench_geometry --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include "defects/Sampling.h"
#include "defects/SolidBuilder.h"
#include "scene/SceneLoader.h"

using namespace ltm;

namespace {

const char* kPaperLens = R"(
object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
)";

const char* kPaperWithDefects = R"(
object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
defects:
  - {type: bubble, center: [0.0, 0.0, 0.0], radius: 0.1}
  - {type: bubble, center: [4.0, 0.0, 0.0], radius: 0.1}
  - {type: bubble, center: [8.0, 0.0, 0.0], radius: 0.1}
  - {type: scratch, surface: front, start: [-5.0, -3.0], end: [5.0, -1.0], width: 0.05, depth: 0.02, profile: V}
)";

void count_triangles(benchmark::State& state, const Solid& s) {
    state.counters["triangles"] = static_cast<double>(s.mesh.num_triangles());
    state.counters["booleans"] = s.boolean_operations;
}

// Parse + mesh of the defect-free paper lens: the set-up cost of every defect-free run.
void BM_SetupDefectFree(benchmark::State& state) {
    Solid s;
    for (auto _ : state) {
        const Scene scene = parse_scene(kPaperLens, "bench");
        s = build_solid(Lens(scene.object.lens), scene.defects, scene.mesh);
        benchmark::DoNotOptimize(s.mesh.vertices.data());
    }
    count_triangles(state, s);
}
BENCHMARK(BM_SetupDefectFree)->Unit(benchmark::kMillisecond);

// Three enclosed bubbles and a 20 um scratch: the bubbles are appended as cavities, the scratch
// is corefined (arg 0); arg 1 forces corefinement of all four.
void BM_PaperThreeBubblesOneScratch(benchmark::State& state) {
    Scene scene = parse_scene(kPaperWithDefects, "bench");
    scene.mesh.always_boolean = state.range(0) != 0;
    Solid s;
    for (auto _ : state) {
        s = build_solid(Lens(scene.object.lens), scene.defects, scene.mesh);
        benchmark::DoNotOptimize(s.mesh.vertices.data());
    }
    count_triangles(state, s);
}
BENCHMARK(BM_PaperThreeBubblesOneScratch)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The object tessellation alone against the chord tolerance (mm).
void BM_TessellateLens(benchmark::State& state) {
    const Lens lens({50, -50, 6, 25, 1.5168});
    MeshOptions opt;
    opt.chord_tolerance = 1e-3 / static_cast<double>(state.range(0));
    Solid s;
    for (auto _ : state) s = build_solid(lens, {}, opt);
    count_triangles(state, s);
}
BENCHMARK(BM_TessellateLens)->Arg(1)->Arg(10)->Arg(100)->Unit(benchmark::kMillisecond);

// 1000 random bubbles, forced through corefinement.
void BM_ThousandBubblesCorefined(benchmark::State& state) {
    const Lens lens({50, -50, 6, 25, 1.5168});
    BubblePopulation p;
    p.count = 1000;
    p.min_radius = 0.02;
    p.max_radius = 0.08;
    p.min_clearance = 0.005;
    const auto bubbles = sample_bubbles(lens, p);
    MeshOptions opt;
    opt.always_boolean = true;
    Solid s;
    for (auto _ : state) s = build_solid(lens, bubbles, opt);
    count_triangles(state, s);
}
BENCHMARK(BM_ThousandBubblesCorefined)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
