// Rendering the light transport matrix: reproducibility, representation agreement and robustness
// on stress scenes.
#include <gtest/gtest.h>

#include <cstring>
#include <set>
#include <thread>

#include "scene/SceneLoader.h"
#include "tests/SceneFixture.h"
#include "trace/Render.h"

using namespace ltm;

namespace {

// The paper's lens and three bubbles, at a reduced resolution.
const char* kBubbles = R"(
object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
defects:
  - {type: bubble, center: [0.0, 0.0, 0.0], radius: 0.4}
  - {type: bubble, center: [4.0, 0.0, 0.0], radius: 0.4}
  - {type: bubble, center: [8.0, 0.0, 0.0], radius: 0.4}
camera: {resolution: [24, 24], size: [25.0, 25.0], numerical_aperture: 0.02, samples_per_pixel: 36}
display: {resolution: [60, 60], size: [100.0, 100.0], z: 60.0}
seed: 7
)";

using test::Built;
using test::build;

bool identical(const CsrMatrix& a, const CsrMatrix& b) {
    return a.rows == b.rows && a.cols == b.cols && a.indptr == b.indptr && a.indices == b.indices &&
           a.data.size() == b.data.size() &&
           std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0;
}

}  // namespace

TEST(Render, BitIdenticalWhateverTheThreadCount) {
    const Built b = build(kBubbles);
    for (auto rep : {Representation::Refined, Representation::Analytic}) {
        TracerOptions o;
        o.representation = rep;
        const Tracer t(b.scene, b.solid, o);
        RenderOptions one, two, four;
        one.threads = 1;
        two.threads = 2;
        four.threads = 4;
        const RenderResult r1 = render(t, one), r2 = render(t, two), r4 = render(t, four);
        EXPECT_EQ(r1.T.check(), "");
        EXPECT_TRUE(identical(r1.T, r2.T)) << to_string(rep);
        EXPECT_TRUE(identical(r1.T, r4.T)) << to_string(rep);
        EXPECT_EQ(r1.stats.segments, r2.stats.segments);
        EXPECT_EQ(r1.stats.display_weight, r4.stats.display_weight);
        // A different seed gives a different estimate.
        RenderOptions other = one;
        other.stream = 1;
        EXPECT_FALSE(identical(r1.T, render(t, other).T));
    }
}

TEST(Render, ConcurrentRendersInOneProcessShareNoThreadState) {
    // Two renders at once from two threads, with different thread counts: each gives the bytes of
    // a render alone (render() keeps no process-wide state such as tbb::global_control).
    const Built b = build(kBubbles);
    const Tracer t(b.scene, b.solid, {});
    RenderOptions one;
    one.threads = 1;
    const RenderResult alone = render(t, one);
    RenderResult a, c;
    RenderOptions two;
    two.threads = 2;
    std::thread ta([&] { a = render(t, one); });
    std::thread tc([&] { c = render(t, two); });
    ta.join();
    tc.join();
    EXPECT_TRUE(identical(alone.T, a.T));
    EXPECT_TRUE(identical(alone.T, c.T));
}

TEST(Render, APixelSubsetGetsExactlyTheRowsOfTheFullRender) {
    const Built b = build(kBubbles);
    const Tracer t(b.scene, b.solid, {});
    RenderOptions full_options;
    full_options.track_defects = true;
    const RenderResult full = render(t, full_options);
    std::vector<long> subset;
    for (long k = 3; k < full.T.rows; k += 7) subset.push_back(k);
    RenderOptions part_options = full_options;
    part_options.pixels = &subset;
    const RenderResult part = render(t, part_options);
    ASSERT_EQ(part.T.check(), "");
    const std::set<long> in(subset.begin(), subset.end());
    for (long k = 0; k < full.T.rows; ++k) {
        const auto b0 = part.T.indptr[static_cast<size_t>(k)], b1 = part.T.indptr[static_cast<size_t>(k) + 1];
        const auto f0 = full.T.indptr[static_cast<size_t>(k)], f1 = full.T.indptr[static_cast<size_t>(k) + 1];
        if (!in.count(k)) {
            EXPECT_EQ(b0, b1) << "pixel " << k << " is not in the subset";
            continue;
        }
        ASSERT_EQ(b1 - b0, f1 - f0) << "pixel " << k;
        for (auto i = b0, j = f0; i < b1; ++i, ++j) {
            EXPECT_EQ(part.T.indices[static_cast<size_t>(i)], full.T.indices[static_cast<size_t>(j)]);
            EXPECT_EQ(part.T.data[static_cast<size_t>(i)], full.T.data[static_cast<size_t>(j)]);
        }
        const auto pc = dense_defect_paths(part, full.T.rows, 3), fc = dense_defect_paths(full, full.T.rows, 3);
        for (int d = 0; d < 3; ++d)
            EXPECT_EQ(pc[static_cast<size_t>(k * 3 + d)], fc[static_cast<size_t>(k * 3 + d)]);
    }
    std::vector<long> unsorted{5, 2};
    part_options.pixels = &unsorted;
    EXPECT_THROW(render(t, part_options), std::invalid_argument);
}

TEST(Render, DefectCountsAreTheSamplesWhosePathsMetEachDefectFirst) {
    // The counts, recomputed path by path with the render's own random streams (Rng(seed, k, s),
    // the camera's permutation): the bookkeeping of PathResult::defect, not its physics (that is
    // study_ground_truth's window test).
    const Built b = build(kBubbles);
    const Tracer t(b.scene, b.solid, {});
    RenderOptions o;
    o.track_defects = true;
    const RenderResult r = render(t, o);
    ASSERT_TRUE(r.tracked_defects);
    const auto counts = dense_defect_paths(r, t.camera().pixels(), 3);
    const TelecentricCamera& cam = t.camera();
    const std::uint64_t seed = render_seed(b.scene, o);
    long seen = 0;
    for (long k = 0; k < cam.pixels(); ++k) {
        std::uint32_t expect[3] = {0, 0, 0};
        const std::vector<int> perm = cam.permutation(k, seed);
        PathStats stats;
        for (int s = 0; s < cam.samples_per_pixel(); ++s) {
            Rng rng(seed, static_cast<std::uint64_t>(k), static_cast<std::uint64_t>(s));
            Vec3 org, dir;
            cam.sample(k, s, perm, rng, org, dir);
            const PathResult p = t.sample_path(org, dir, rng, stats);
            if (p.defect >= 0) ++expect[p.defect];
        }
        for (int d = 0; d < 3; ++d) {
            EXPECT_EQ(counts[static_cast<size_t>(k * 3 + d)], expect[d]) << "pixel " << k << " defect " << d;
            seen += expect[d];
        }
    }
    EXPECT_GT(seen, 0);  // the bubbles (r = 0.4 mm, pixels of 1.04 mm) are met
}

TEST(Render, MixedSeedsDoNotCollideAcrossNeighbouringScenes) {
    // seed + stream would give (1, 2) and (2, 1) the same stream; mix_seed keeps all 32 x 32
    // neighbouring pairs apart, and a stream of 0 is not the seed itself.
    std::set<std::uint64_t> seen;
    for (std::uint64_t a = 0; a < 32; ++a)
        for (std::uint64_t b = 0; b < 32; ++b) seen.insert(mix_seed(a, b));
    EXPECT_EQ(seen.size(), 32u * 32u);
    EXPECT_NE(mix_seed(5, 0), 5u);
}

TEST(Render, RefinedMeshAndAnalyticPrimitivesGiveTheSamePaths) {
    // Refinement makes every hit exact, so the two representations must agree bit for bit.
    const Built b = build(kBubbles);
    TracerOptions refined, analytic;
    refined.representation = Representation::Refined;
    analytic.representation = Representation::Analytic;
    const RenderResult a = render(Tracer(b.scene, b.solid, refined), {});
    const RenderResult c = render(Tracer(b.scene, b.solid, analytic), {});
    EXPECT_TRUE(identical(a.T, c.T));
    EXPECT_EQ(a.stats.leaks_unresolved, 0u);
    // The mesh-only representation approximates: same size of problem, different values.
    TracerOptions mesh;
    mesh.representation = Representation::MeshOnly;
    const RenderResult m = render(Tracer(b.scene, b.solid, mesh), {});
    EXPECT_FALSE(identical(a.T, m.T));
    EXPECT_EQ(m.T.rows, a.T.rows);
}

TEST(Render, RowsHoldOnlyTheirNonzerosAndSumToAtMostOne) {
    const Built b = build(kBubbles);
    const RenderResult r = render(Tracer(b.scene, b.solid), {});
    ASSERT_EQ(r.T.check(), "");
    EXPECT_EQ(r.T.rows, 24 * 24);
    EXPECT_EQ(r.T.cols, 60 * 60);
    // Without absorption or roulette every path has weight 1: a row sums to at most 1 (all of the
    // pixel's throughput), and each entry is a multiple of 1 / spp.
    for (long k = 0; k < r.T.rows; ++k) {
        double sum = 0;
        for (auto i = r.T.indptr[static_cast<size_t>(k)]; i < r.T.indptr[static_cast<size_t>(k) + 1]; ++i) {
            sum += r.T.data[static_cast<size_t>(i)];
            const double n = r.T.data[static_cast<size_t>(i)] * 36.0;
            EXPECT_NEAR(n, std::round(n), 1e-5);
        }
        EXPECT_LE(sum, 1.0 + 1e-6);
    }
    EXPECT_LE(r.T.nnz(), static_cast<size_t>(24 * 24 * 36));
}

TEST(Render, StressScenesProduceNoNaN) {
    // Pits, scratches crossing them, overlapping and touching bubbles, a particle, grazing
    // illumination (NA 0.9), TIR-heavy geometry: every path must stay finite.
    const char* stress = R"(
object: {type: lens, r1: 20.0, r2: -20.0, center_thickness: 10.0, diameter: 25.0, ior: 1.8}
defects:
  - {type: bubble, center: [0.0, 0.0, -4.95], radius: 0.3, surface_breaking: true}
  - {type: scratch, surface: front, start: [-3.0, 0.0], end: [3.0, 0.5], width: 0.05, depth: 0.02, profile: V}
  - {type: scratch, surface: back, arc: {center: [0.0, 0.0], radius: 4.0, start_angle: 0, end_angle: 270}, width: 0.04, depth: 0.03, profile: U}
  - {type: bubble, center: [2.0, 2.0, 0.0], radius: 0.5}
  - {type: bubble, center: [2.6, 2.0, 0.0], radius: 0.3}
  - {type: bubble, center: [-2.0, -2.0, 0.0], radius: 0.2}
  - {type: bubble, center: [-1.7, -2.0, 0.0], radius: 0.1}
  - {type: particle, center: [-4.0, 3.0, 0.5], radius: 0.3}
camera: {resolution: [30, 30], size: [26.0, 26.0], numerical_aperture: 0.9, samples_per_pixel: 16}
display: {resolution: [40, 40], size: [200.0, 200.0], z: 40.0}
)";
    const Built b = build(stress);
    const RenderResult r = render(Tracer(b.scene, b.solid), {});
    EXPECT_EQ(r.stats.nan_events, 0u);
    EXPECT_EQ(r.stats.leaks_unresolved, 0u);
    EXPECT_GT(r.stats.tir, 0u);
    EXPECT_GT(r.stats.absorbed_particle, 0u);
    EXPECT_EQ(r.T.check(), "");
}
