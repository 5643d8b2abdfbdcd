// Tetrahedral meshing (geometry/TetMesh.h): a sphere of radius 2.5 mm with the smooth profile
// n = 1.5 + 0.02 (1 - rho^2)^2, rho = |x| / 2.5 (tests/SmoothProfile.h, with its rigorous local
// Hessian bound of n^2), at tolerances 1e-3, 1e-4 and 1e-5 on n^2 (the argument is the exponent).
//   build/bench/bench_tetgen
//   build/bench/bench_tetgen --benchmark_filter=Global   (the whole-ball bound instead, for comparison)
// Each case runs once (a mesh takes seconds to minutes); the second argument is max_tets in
// millions. At 1e-5 the mesh has 3.3e7 tetrahedra: measured 322 s and 6.5 GB peak with
// max_tets = 40 (million), on one core of an AMD EPYC. The registered 1e-5 case is capped at 2
// million instead, so a default run stays small; it shows the refusal (TetGen stopped by its
// Steiner point budget). Change its cap to 40 to mesh it in full.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

#include "geometry/Tessellate.h"
#include "geometry/TetMesh.h"
#include "tests/SmoothProfile.h"

using namespace ltm;

namespace {

constexpr double kRadius = 2.5;

TetRegion smooth_sphere(double tolerance, bool local_bound, size_t max_tets) {
    static const test::SmoothProfile field{1.5, 0.02, kRadius};
    TetRegion r;
    r.name = "bench";
    // An icosphere of chord error <= 5 um (level 4, 5120 triangles), inscribed in |x| <= 2.5.
    r.boundary = tessellate_ellipsoid({0, 0, 0}, Mat3::identity(), {kRadius, kRadius, kRadius}, 0.005, 0).mesh;
    r.n2 = [](const Vec3& x) { return field.n2(x); };
    if (local_bound) {
        r.hessian_bound = [](const Vec3& c, double radius) { return field.hessian_bound(c, radius); };
    } else {
        const double m = field.global_hessian_bound();
        r.hessian_bound = [m](const Vec3&, double) { return m; };
    }
    r.tolerance = tolerance;
    r.max_tets = max_tets;
    return r;
}

void run(benchmark::State& state, bool local_bound) {
    const double tolerance = std::pow(10.0, -static_cast<double>(state.range(0)));
    const auto max_tets = static_cast<size_t>(state.range(1)) * 1'000'000;
    const TetRegion region = smooth_sphere(tolerance, local_bound, max_tets);
    TetMesh mesh;
    for (auto _ : state) {
        try {
            mesh = tetrahedralize(region);
        } catch (const TetGenError& e) {
            state.SkipWithError(e.what());
            return;
        }
        benchmark::DoNotOptimize(mesh.tets.data());
    }
    state.counters["tets"] = static_cast<double>(mesh.num_tets());
    state.counters["vertices"] = static_cast<double>(mesh.vertices.size());
    state.counters["error_bound"] = mesh.error_bound;
}

void BM_TetgenSmoothSphere(benchmark::State& state) { run(state, true); }
BENCHMARK(BM_TetgenSmoothSphere)
    ->Args({3, 20})
    ->Args({4, 20})
    ->Args({5, 2})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

void BM_TetgenSmoothSphereGlobalBound(benchmark::State& state) { run(state, false); }
BENCHMARK(BM_TetgenSmoothSphereGlobalBound)->Args({3, 20})->Args({4, 20})->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
