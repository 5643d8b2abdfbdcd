// Rendering the light transport matrix: reproducibility, representation agreement and robustness
// on stress scenes.
#include <gtest/gtest.h>

#include <cstring>

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
        other.seed_offset = 1;
        EXPECT_FALSE(identical(r1.T, render(t, other).T));
    }
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
