// The split estimator (scene.tracing, Tracer::sample_paths): its deterministic branches against
// closed forms, total internal reflection left unsplit, depth 0 as the sample estimator bit for
// bit, and reproducibility whatever the thread count. Its unbiasedness is validation_render's.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/SceneFixture.h"
#include "tests/Tolerances.h"
#include "trace/Render.h"

using namespace ltm;

namespace {

using test::Built;
using test::build;

// A flat window (n = 1.5) in front of a large display.
const char* kWindow = R"(
object: {type: window, thickness: 4.0, diameter: 40.0, ior: 1.5}
camera: {resolution: [12, 12], size: [20.0, 20.0], numerical_aperture: 0.01, samples_per_pixel: 32}
display: {resolution: [40, 40], size: [200.0, 200.0], z: 30.0}
seed: 5
)";

// A plano-convex lens of dense flint with a bubble and an absorbing particle: curved and flat
// faces, ghosts, bubble walls (and total internal reflection inside the bubble), absorbed branches.
const char* kLens = R"(
object: {type: lens, r1: 40.0, r2: inf, center_thickness: 7.0, diameter: 24.0, ior: 1.72}
defects:
  - {type: bubble, center: [1.0, -1.0, 0.5], radius: 1.2}
  - {type: particle, center: [-5.0, 3.0, 1.0], radius: 0.7}
camera: {resolution: [18, 18], size: [25.0, 25.0], numerical_aperture: 0.04, samples_per_pixel: 32}
display: {resolution: [40, 40], size: [90.0, 90.0], z: 55.0}
seed: 9
)";

Built with_estimator(const char* yaml, Estimator e, int depth) {
    Built b = build(yaml);
    b.scene.tracing.estimator = e;
    b.scene.tracing.split_depth = depth;
    return b;
}

}  // namespace

TEST(Split, WindowAtNormalIncidenceSumsTheIncoherentSeriesTruncatedAtTheDepth) {
    // At normal incidence on a window every interface reflects R = ((n - 1) / (n + 1))^2 and
    // transmits T = 1 - R. The incoherent multiple-reflection (Airy) sum of what reaches the
    // display is T^2 sum_j (R^2)^j (Born & Wolf 7.6; j = 0 the direct image, j the j-th ghost).
    // Splitting follows one chain: front (its reflection leaves toward the camera), back (the
    // transmitted branch is the direct image), front again from inside (its transmission leaves
    // toward the camera), back (the first ghost), ... so with depth D, the ghosts j with 2 j + 2 <= D
    // are deterministic branches, j = 0 .. floor(D/2) - 1, each exactly T^2 R^{2j}; the last
    // reflected branch goes on sampled (random_choices > 0). D splits make D + 1 branches.
    const double n = 1.5, R = std::pow((n - 1) / (n + 1), 2), T = 1 - R;
    for (int depth : {0, 1, 2, 3, 4, 5, 6, 8, 12, 16}) {
        const Built b = with_estimator(kWindow, Estimator::Split, depth);
        const Tracer tracer(b.scene, b.solid);
        Rng rng(1, 2, 3);
        PathStats stats;
        std::vector<PathResult> out;
        tracer.sample_paths({1.0, 2.0, -10.0}, {0.0, 0.0, 1.0}, rng, stats, out);
        const long below = tracer.display().pixel(1.0, 2.0);  // a normal ray is not displaced
        double sum = 0, expected = 0;
        int exact = 0;
        for (const PathResult& r : out) {
            if (r.random_choices > 0 || r.pixel < 0) continue;
            const double ghost = T * T * std::pow(R * R, exact);  // branches come in order j = 0, 1, ...
            EXPECT_NEAR(r.weight, ghost, ghost * tol::split_exact_relative(depth)) << "depth " << depth << " ghost " << exact;
            EXPECT_EQ(r.pixel, below) << "depth " << depth;
            sum += r.weight;
            expected += ghost;
            ++exact;
        }
        EXPECT_EQ(exact, depth / 2) << "depth " << depth;
        EXPECT_NEAR(sum, expected, expected * tol::split_exact_relative(depth)) << "depth " << depth;
        if (depth >= 2) {
            // The closed form, not the loop above: T^2 (1 - R^(2J)) / (1 - R^2), J = floor(D / 2).
            const double series = T * T * (1 - std::pow(R * R, depth / 2)) / (1 - R * R);
            EXPECT_NEAR(sum, series, series * tol::split_exact_relative(depth)) << "depth " << depth;
        }
        EXPECT_EQ(stats.paths, 1u);
        EXPECT_EQ(stats.splits, static_cast<std::uint64_t>(depth));
        EXPECT_EQ(out.size(), static_cast<size_t>(depth + 1));
        EXPECT_EQ(stats.branches, static_cast<std::uint64_t>(depth + 1));
    }
}

TEST(Split, TotalInternalReflectionIsNoSplit) {
    // A ray at 60 degrees enters the window's front face at x = 18 mm (rim at 20 mm), refracts to
    // asin(sin 60 / 1.5) = 35.3 degrees, meets the polished rim at 54.7 degrees from its normal,
    // beyond the critical angle asin(1 / 1.5) = 41.8: total internal reflection; then it leaves
    // through the back face. Its principal path has two Fresnel interactions and one TIR. With
    // split_depth 2 the first branch (transmitted at both) must be deterministic, its weight the
    // product of the two transmittances: a TIR that used up a split would leave the back face
    // to a random choice.
    const Built b = with_estimator(kWindow, Estimator::Split, 2);
    const Tracer tracer(b.scene, b.solid);
    const double s60 = std::sqrt(3.0) / 2;
    const Vec3 d{s60, 0.0, 0.5}, on_front{18.0, 0.0, -2.0};
    const Vec3 origin = on_front - d * 5.0;
    const PrincipalPath p = tracer.principal_path(origin, d);
    ASSERT_EQ(p.tir, 1);
    ASSERT_EQ(p.vertices.size(), 3u);  // front, rim, back
    ASSERT_TRUE(p.display_hit);
    Rng rng(4, 5, 6);
    PathStats stats;
    std::vector<PathResult> out;
    tracer.sample_paths(origin, d, rng, stats, out);
    ASSERT_FALSE(out.empty());
    EXPECT_EQ(out[0].random_choices, 0);
    // The same two products; principal_path normalises the direction once more (an ulp apart).
    EXPECT_NEAR(out[0].weight, p.transmission, p.transmission * tol::split_exact_relative(2));
    EXPECT_EQ(out[0].pixel, static_cast<long>(p.p) * b.scene.display.resolution[0] + p.q);
    EXPECT_EQ(stats.splits, 2u);
    EXPECT_GE(stats.tir, 1u);
}

TEST(Split, ADepthBeyondTheStackIsRefusedNotClamped) {
    const Built b = with_estimator(kWindow, Estimator::Split, kMaxSplitDepth + 1);
    EXPECT_THROW(Tracer(b.scene, b.solid), std::invalid_argument);
    const Built negative = with_estimator(kWindow, Estimator::Split, -1);
    EXPECT_THROW(Tracer(negative.scene, negative.solid), std::invalid_argument);
}

TEST(Split, DepthZeroIsTheSampleEstimatorBitForBit) {
    // No split left from the start: every sample is the sampled path, with the same draws.
    const Built sample = with_estimator(kLens, Estimator::Sample, kDefaultSplitDepth);
    const Built split0 = with_estimator(kLens, Estimator::Split, 0);
    RenderOptions o;
    o.track_defects = true;
    const RenderResult a = render(Tracer(sample.scene, sample.solid), o);
    const RenderResult c = render(Tracer(split0.scene, split0.solid), o);
    EXPECT_TRUE(bit_identical(a.T, c.T));
    EXPECT_EQ(a.stats.segments, c.stats.segments);
    EXPECT_EQ(c.stats.splits, 0u);
    ASSERT_EQ(a.defect_paths.size(), c.defect_paths.size());
    for (size_t i = 0; i < a.defect_paths.size(); ++i) EXPECT_EQ(a.defect_paths[i].paths, c.defect_paths[i].paths);
}

TEST(Split, BitIdenticalWhateverTheThreadCountAndDeterministicPerSeed) {
    const Built b = with_estimator(kLens, Estimator::Split, 6);
    for (auto rep : {Representation::Refined, Representation::Analytic}) {
        TracerOptions to;
        to.representation = rep;
        const Tracer t(b.scene, b.solid, to);
        RenderOptions one, two;
        one.threads = 1;
        two.threads = 2;
        const RenderResult r1 = render(t, one), r2 = render(t, two), again = render(t, one);
        EXPECT_EQ(r1.T.check(), "");
        EXPECT_GT(r1.stats.splits, 0u);
        EXPECT_GT(r1.stats.branches, r1.stats.paths);
        EXPECT_TRUE(bit_identical(r1.T, r2.T)) << to_string(rep);
        EXPECT_TRUE(bit_identical(r1.T, again.T)) << to_string(rep);
        EXPECT_EQ(r1.stats.display_weight, r2.stats.display_weight);
        EXPECT_EQ(r1.stats.branches, r2.stats.branches);
        // The direct render of a pattern too (its per-sample sums of branches).
        std::vector<float> x(static_cast<size_t>(t.display().pixels()));
        for (size_t l = 0; l < x.size(); ++l) x[l] = static_cast<float>((l * 7) % 5) / 4.0f;
        one.pattern = two.pattern = &x;
        const RenderResult y1 = render(t, one), y2 = render(t, two);
        EXPECT_EQ(y1.image, y2.image);
        EXPECT_EQ(y1.image_stderr, y2.image_stderr);
        // Another stream is another estimate.
        RenderOptions other;
        other.threads = 1;
        other.stream = 1;
        EXPECT_FALSE(bit_identical(r1.T, render(t, other).T));
    }
}

TEST(Split, DefectCountsAreTheSamplesSomeBranchOfWhichMetTheDefectFirst) {
    // With splitting a sample counts once for each defect that one of its branches met first
    // (so the counts stay numbers of samples, <= spp), recomputed here sample by sample with the
    // render's streams.
    const Built b = with_estimator(kLens, Estimator::Split, 4);
    const Tracer t(b.scene, b.solid);
    RenderOptions o;
    o.track_defects = true;
    const RenderResult r = render(t, o);
    const auto counts = dense_defect_paths(r, t.camera().pixels(), 2);
    const TelecentricCamera& cam = t.camera();
    const std::uint64_t seed = render_seed(b.scene, o);
    long seen = 0, several = 0;
    std::vector<PathResult> out;
    for (long k = 0; k < cam.pixels(); ++k) {
        std::uint32_t expect[2] = {0, 0};
        PathStats stats;
        for_each_camera_sample(cam, seed, k, [&](int, Rng& rng, const Vec3& org, const Vec3& dir) {
            out.clear();
            t.sample_paths(org, dir, rng, stats, out);
            bool met[2] = {false, false};
            int with_defect = 0;
            for (const PathResult& p : out)
                if (p.defect >= 0) {
                    met[p.defect] = true;
                    ++with_defect;
                }
            several += with_defect > 1;
            for (int d = 0; d < 2; ++d) expect[d] += met[d];
        });
        for (int d = 0; d < 2; ++d) {
            EXPECT_EQ(counts[static_cast<size_t>(k * 2 + d)], expect[d]) << "pixel " << k << " defect " << d;
            EXPECT_LE(expect[d], static_cast<std::uint32_t>(cam.samples_per_pixel()));
            seen += expect[d];
        }
    }
    EXPECT_GT(seen, 0);
    EXPECT_GT(several, 0);  // samples with several branches through a bubble: counted once
}
