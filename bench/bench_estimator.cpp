// Error per second, not paths per second: the sample estimator against the
// split estimator (scene.tracing, docs/estimators.md) on the paper's lens.
//
// For each estimator, the scene is rendered --reps times with independent random streams
// (RenderOptions::stream = 1, 2, ...); the features of every T (features/Features.h) give, per
// camera pixel, a sample variance across the repetitions. Printed per feature (BrightField,
// ScatterCount, MeanX, MeanY: the deflection map of a defect-free object is its mean position):
// the feature's mean value, its variance averaged over the pixels (and the median over the pixels,
// which rim pixels do not dominate), the median render time, the product variance x seconds (the
// variance a render would have if run for one second: Monte Carlo variance falls as 1 / time),
// and that product relative to the sample estimator's (below 1: the split estimator reaches a
// given error sooner).
//
// Scenes: defect-free = scenes/paper/defect-free.yaml; bubbles = bench_trace's paper scene (three
// bubbles of 0.1 mm radius), whose features include the bubbles' scatter. Both at --samples
// samples per pixel (default 64, the issue's).
//
// Usage: bench_estimator [--threads N] [--reps R] [--samples S] [--quick]
//        (--quick: 40 x 40 camera pixels, for a smoke run)
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/BenchSupport.h"
#include "features/Features.h"
#include "scene/SceneLoader.h"
#include "scene/SceneSolid.h"
#include "trace/Render.h"

using namespace ltm;
using bench::median;

namespace {

const std::vector<std::string> kFeatures{"BrightField", "ScatterCount", "MeanX", "MeanY"};

struct Measured {
    std::string name;
    std::vector<double> value;     // per feature, averaged over the pixels and repetitions
    std::vector<double> variance;  // per feature, averaged over the pixels
    std::vector<double> median_variance;  // per feature, the median over the pixels
    double seconds = 0;            // median render time
    double branches_per_path = 0;
};

// Per-pixel sample variance across repetitions, by Welford's update (stable for values that vary
// little around a large mean, as MeanX does), averaged over the pixels where the feature is finite
// in every repetition.
class Spread {
public:
    explicit Spread(size_t pixels) : n_(pixels, 0), mean_(pixels, 0.0), m2_(pixels, 0.0) {}
    void add(const std::vector<float>& v) {
        for (size_t k = 0; k < v.size(); ++k) {
            if (!std::isfinite(v[k])) continue;
            const double x = v[k], d = x - mean_[k];
            mean_[k] += d / ++n_[k];
            m2_[k] += d * (x - mean_[k]);
        }
    }
    // Over the pixels where the feature was finite in every repetition: the mean value, the mean
    // and the median of the per-pixel sample variances.
    void summary(int reps, double& value, double& mean_variance, double& median_variance) const {
        std::vector<double> v;
        double sum = 0;
        for (size_t k = 0; k < n_.size(); ++k)
            if (n_[k] == reps) {
                v.push_back(m2_[k] / (reps - 1));
                sum += mean_[k];
            }
        if (v.empty()) {
            value = mean_variance = median_variance = NAN;
            return;
        }
        value = sum / static_cast<double>(v.size());
        double total = 0;
        for (double x : v) total += x;
        mean_variance = total / static_cast<double>(v.size());
        median_variance = median(v);
    }

private:
    std::vector<int> n_;
    std::vector<double> mean_, m2_;
};

Measured measure(Scene scene, const Solid& solid, const TracingDesc& tracing, const bench::Args& args) {
    scene.tracing = tracing;
    TracerOptions to;
    to.representation = Representation::Analytic;  // no defect cuts the glass in either scene
    const Tracer tracer(scene, solid, to);
    const int N = scene.camera.resolution[0], M = scene.camera.resolution[1];
    const DisplayGrid grid{scene.display.resolution[0], scene.display.resolution[1], scene.display.size[0],
                           scene.display.size[1]};
    std::vector<Spread> spread(kFeatures.size(), Spread(static_cast<size_t>(N) * static_cast<size_t>(M)));
    std::vector<double> times;
    Measured out;
    out.name = tracing.estimator == Estimator::Split ? "split " + std::to_string(tracing.split_depth) : "sample";
    for (int r = 0; r < args.reps; ++r) {
        RenderOptions ro;
        ro.threads = args.threads;
        ro.stream = static_cast<std::uint64_t>(r) + 1;
        const RenderResult res = render(tracer, ro);
        times.push_back(res.seconds);
        out.branches_per_path = static_cast<double>(res.stats.branches) / static_cast<double>(res.stats.paths);
        const FeatureImages f = compute_features(res.T, N, M, grid, FeatureOptions{}, nullptr);
        for (size_t i = 0; i < kFeatures.size(); ++i) spread[i].add(f.channel(kFeatures[i]));
    }
    out.seconds = median(times);
    for (const Spread& s : spread) {
        double value = 0, mean_variance = 0, median_variance = 0;
        s.summary(args.reps, value, mean_variance, median_variance);
        out.value.push_back(value);
        out.variance.push_back(mean_variance);
        out.median_variance.push_back(median_variance);
    }
    return out;
}

void run_scene(const char* label, Scene scene, const bench::Args& args) {
    if (args.quick) scene.camera.resolution = {40, 40};
    scene.camera.samples_per_pixel = static_cast<int>(args.samples);
    const Solid solid = build_solid(scene, nullptr, /*surfaces_only=*/true);
    std::printf("\n%s: %d x %d camera pixels, %d samples per pixel, %d repetitions, %d threads\n", label,
                scene.camera.resolution[0], scene.camera.resolution[1], scene.camera.samples_per_pixel, args.reps,
                args.threads);
    std::vector<Measured> rows;
    TracingDesc sample;
    rows.push_back(measure(scene, solid, sample, args));
    for (int depth : {2, 4, 6, 8}) {
        TracingDesc split;
        split.estimator = Estimator::Split;
        split.split_depth = depth;
        rows.push_back(measure(scene, solid, split, args));
    }
    const Measured& base = rows.front();
    std::printf("%-9s %8s %9s\n", "estimator", "seconds", "branches");
    for (const Measured& m : rows) std::printf("%-9s %8.3f %9.2f\n", m.name.c_str(), m.seconds, m.branches_per_path);
    for (size_t i = 0; i < kFeatures.size(); ++i) {
        std::printf("%s\n  %-9s %12s %12s %12s %12s %10s %12s\n", kFeatures[i].c_str(), "estimator", "mean value",
                    "mean var", "median var", "var x s", "ratio", "median ratio");
        for (const Measured& m : rows) {
            const double vs = m.variance[i] * m.seconds, base_vs = base.variance[i] * base.seconds;
            const double ms = m.median_variance[i] * m.seconds, base_ms = base.median_variance[i] * base.seconds;
            std::printf("  %-9s %12.6g %12.4e %12.4e %12.4e %10.4f %12.4f\n", m.name.c_str(), m.value[i], m.variance[i],
                        m.median_variance[i], vs, vs / base_vs, ms / base_ms);
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    bench::Args defaults;
    defaults.reps = 8;
    defaults.samples = 64;
    const bench::Args args = bench::parse_args(argc, argv, defaults);
    if (args.reps < 2) {
        std::fprintf(stderr, "bench_estimator: --reps must be at least 2 (a variance across repetitions)\n");
        return 2;
    }
    std::printf("variance across --reps renders with independent streams, averaged over the pixels;\n"
                "seconds: median render time; ratio: (var x s) / (var x s of the sample estimator)\n");
    run_scene("defect-free (scenes/paper/defect-free.yaml)",
              load_scene(bench::source_dir() + "/scenes/paper/defect-free.yaml"), args);
    run_scene("bubbles (bench_trace's paper scene)", parse_scene(bench::paper_scene(100, 64), "bench_estimator"), args);
    return 0;
}
