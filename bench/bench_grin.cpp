// Graded-index benchmarks. Medians of repeated runs in one process, on this machine:
//   a. closed-form GRIN paths against homogeneous ones of the same object, per thread: the
//      Luneburg sphere against a homogeneous ball, a GRIN rod against a plain window, a general
//      quadratic field against the plain lens (paths/s and the ratio);
//   b. TetGen: time and tetrahedra for the 2.5 mm, delta_n = 0.02 inclusion of
//      scenes/examples/inclusion-smooth.yaml and for the striae of scenes/examples/striae.yaml, at
//      the default index tolerance;
//   c. tetrahedron crossings per second per thread, walking rays through that inclusion;
//   d. the striae example rendered against the same lens without striae;
//   e. display-hit error against the GRIN reference (validation/GrinReference.h) and time, over
//      index tolerances (CSV: grin_error_vs_time.csv; bench/plot.py draws it).
// Usage: bench_grin [--threads N] [--reps R] [--out DIR] [--quick]
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <string>
#include <vector>

#include "bench/BenchSupport.h"
#include "scene/SceneLoader.h"
#include "scene/SceneSolid.h"
#include "trace/Render.h"
#include "validation/GrinReference.h"

using namespace ltm;

namespace {

using bench::median;
using bench::now;

struct Setup {
    Scene scene;
    Solid solid;
    double build_seconds = 0;
};
Setup setup(const std::string& yaml) {
    Setup s;
    s.scene = parse_scene(yaml, "bench");
    const double t0 = now();
    s.solid = build_solid(s.scene);
    s.build_seconds = now() - t0;
    return s;
}
Setup load(const std::string& file) {
    Setup s;
    s.scene = load_scene(bench::source_dir() + "/" + file);
    const double t0 = now();
    s.solid = build_solid(s.scene);
    s.build_seconds = now() - t0;
    return s;
}

// Median render time of the scene (analytic representation: no mesh in the way).
double render_seconds(const Setup& s, int threads, int reps, RenderResult* last = nullptr) {
    TracerOptions o;
    o.representation = Representation::Analytic;
    const Tracer t(s.scene, s.solid, o);
    std::vector<double> times;
    for (int i = 0; i < reps; ++i) {
        RenderOptions ro;
        ro.threads = threads;
        RenderResult r = render(t, ro);
        times.push_back(r.seconds);
        if (last) *last = std::move(r);
    }
    return median(times);
}

std::string with_camera(const std::string& object, int n, int spp, double size) {
    return fmt::format("{}\ncamera: {{resolution: [{}, {}], size: [{}, {}], numerical_aperture: 0.002, samples_per_pixel: {}}}\n"
                       "display: {{resolution: [500, 500], size: [100.0, 100.0], z: 60.0}}\n",
                       object, n, n, size, size, spp);
}

std::string inclusion_scene(double tolerance) {
    return fmt::format(R"(
object: {{type: window, thickness: 8.0, diameter: 30.0, ior: 1.5}}
defects:
  - {{type: inhomogeneity, center: [0.0, 0.0, 0.0], radius: 2.5, delta_n: 0.02, profile: smooth}}
display: {{resolution: [500, 500], size: [100.0, 100.0], z: 60.0}}
mesh: {{index_tolerance: {}}}
)",
                       tolerance);
}

}  // namespace

int main(int argc, char** argv) {
    const bench::Args args = bench::parse_args(argc, argv);
    const int threads = args.threads, reps = args.reps;
    const std::string out = args.out;
    const bool quick = args.quick;
    std::printf("threads %d, repetitions %d (medians)\n\n", threads, reps);

    // a. Per thread: one thread, so the ratio is the cost per path.
    {
        const int n = quick ? 50 : 100, spp = 16;
        struct Pair {
            const char* name;
            std::string graded, plain;
            double size;
        } pairs[] = {
            {"Luneburg sphere vs homogeneous ball",
             "object: {type: sphere, radius: 10.0, ior: 1.4142135623730951, index_field: {type: spherical_n2, g: 0.0707106781186548}}",
             "object: {type: sphere, radius: 10.0, ior: 1.4142135623730951}", 20.0},
            {"GRIN rod (radial_n2) vs window",
             "object: {type: window, thickness: 20.0, diameter: 10.0, ior: 1.6, index_field: {type: radial_n2, g: 0.05}}",
             "object: {type: window, thickness: 20.0, diameter: 10.0, ior: 1.6}", 10.0},
            {"linear_n2 window vs window",
             "object: {type: window, thickness: 8.0, diameter: 30.0, ior: 1.5, index_field: {type: linear_n2, gradient: [0.005, 0.0, 0.0]}}",
             "object: {type: window, thickness: 8.0, diameter: 30.0, ior: 1.5}", 25.0},
            {"quadratic_n2 lens vs lens",
             "object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168, index_field: "
             "{type: quadratic_n2, gradient: [0.0, 0.0, 0.002], hessian: [[-0.0008, 0.0, 0.0], [0.0, -0.0004, 0.0], [0.0, 0.0, 0.0]]}}",
             "object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}", 25.0},
        };
        std::printf("a. closed-form GRIN against homogeneous paths, 1 thread, %d x %d x %d spp\n", n, n, spp);
        std::printf("%-40s %14s %14s %8s\n", "scene", "GRIN Mpaths/s", "plain Mpaths/s", "ratio");
        for (const Pair& p : pairs) {
            const Setup g = setup(with_camera(p.graded, n, spp, p.size)), h = setup(with_camera(p.plain, n, spp, p.size));
            const double tg = render_seconds(g, 1, reps), th = render_seconds(h, 1, reps);
            const double paths = double(n) * n * spp;
            std::printf("%-40s %14.3f %14.3f %8.2f\n", p.name, paths / tg / 1e6, paths / th / 1e6, tg / th);
        }
        std::printf("\n");
    }

    // b + c.
    {
        const Setup incl = setup(inclusion_scene(MeshOptions{}.index_tolerance));
        const TetMesh& m = incl.solid.regions.at(0);
        std::printf("b. TetGen at the default index tolerance %g\n", MeshOptions{}.index_tolerance);
        std::printf("   2.5 mm inclusion, delta_n 0.02: %.2f s, %zu tetrahedra, %zu vertices\n", incl.build_seconds,
                    m.num_tets(), m.vertices.size());
        if (!quick) {
            const Setup striae = load("scenes/examples/striae.yaml");
            size_t tets = 0;
            for (const TetMesh& r : striae.solid.regions) tets += r.num_tets();
            std::printf("   striae example (4 regions): %.2f s, %zu tetrahedra\n", striae.build_seconds, tets);
        }
        TracerOptions o;
        o.representation = Representation::Analytic;
        const Tracer t(incl.scene, incl.solid, o);
        std::vector<double> rates;
        std::uint64_t crossings = 0;
        for (int r = 0; r < reps; ++r) {
            PathStats stats;
            Rng rng(1, static_cast<std::uint64_t>(r));
            const double t0 = now();
            for (int i = 0; i < (quick ? 2000 : 20000); ++i) {
                const double x = 4.8 * (rng.uniform() - 0.5), y = 4.8 * (rng.uniform() - 0.5);
                t.sample_path({x, y, -10}, {0, 0, 1}, rng, stats);
            }
            rates.push_back(static_cast<double>(stats.tet_crossings) / (now() - t0));
            crossings = stats.tet_crossings;
        }
        std::printf("c. tetrahedron crossings: %.3g per second per thread (%llu crossings per repetition, whole paths "
                    "timed)\n\n",
                    median(rates), static_cast<unsigned long long>(crossings));
    }

    // d.
    if (!quick) {
        const Setup striae = load("scenes/examples/striae.yaml");
        Setup plain = striae;
        plain.scene.defects.clear();
        plain.solid = build_solid(plain.scene);
        const double ts = render_seconds(striae, threads, reps), tp = render_seconds(plain, threads, reps);
        std::printf("d. striae example, 100 x 100 x 256 spp, %d threads: %.3f s with striae, %.3f s without (ratio %.2f); "
                    "TetGen %.2f s once per scene\n\n",
                    threads, ts, tp, ts / tp, striae.build_seconds);
    }

    // e.
    {
        std::ofstream csv(out + "/grin_error_vs_time.csv");
        csv << "index_tolerance,tetrahedra,tetgen_seconds,trace_seconds,max_display_error_mm,mean_display_error_mm\n";
        std::printf("e. 2.5 mm inclusion: display-hit error against the GRIN reference over index tolerances (625 axial rays)\n");
        std::printf("%14s %12s %10s %10s %14s %14s\n", "tolerance", "tetrahedra", "TetGen s", "trace s", "max err mm",
                    "mean err mm");
        std::vector<double> tolerances{4e-3, 1e-3, 5e-4, 2.5e-4};
        if (!quick) tolerances.push_back(1e-4);
        validation::GrinReference reference(setup(inclusion_scene(1e-3)).scene);
        std::vector<std::pair<Vec3, Vec3>> exact;
        for (int i = -12; i <= 12; ++i)
            for (int j = -12; j <= 12; ++j) {
                const double x = 0.2 * i + 0.013, y = 0.2 * j + 0.007;
                const validation::Path p = reference.principal_path({x, y, -10}, {0, 0, 1});
                exact.push_back({{x, y, -10}, {p.display_x, p.display_y, p.display_hit ? 1.0 : 0.0}});
            }
        for (double tol : tolerances) {
            const Setup s = setup(inclusion_scene(tol));
            TracerOptions o;
            o.representation = Representation::Analytic;
            const Tracer t(s.scene, s.solid, o);
            const double t0 = now();
            double max_e = 0, sum = 0;
            int n = 0;
            for (const auto& [origin, hit] : exact) {
                const PrincipalPath p = t.principal_path(origin, {0, 0, 1});
                if (!p.display_hit || hit.z == 0) continue;
                const double e = std::hypot(p.x - hit.x, p.y - hit.y);
                max_e = std::max(max_e, e);
                sum += e;
                ++n;
            }
            const double trace_s = now() - t0;
            std::printf("%14g %12zu %10.2f %10.3f %14.3g %14.3g\n", tol, s.solid.regions[0].num_tets(), s.build_seconds,
                        trace_s, max_e, sum / n);
            csv << tol << "," << s.solid.regions[0].num_tets() << "," << s.build_seconds << "," << trace_s << "," << max_e
                << "," << sum / n << "\n";
        }
    }
    return 0;
}
