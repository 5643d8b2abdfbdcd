// Thin features and scale: the refined tracer against the independent reference solver for a
// bubble under 1 um of glass, and for every lens kind from 1e-3 mm to 1e3 mm; a 10 um scratch
// is seen by rays aimed into it. Tolerances: validation/ValidationTolerance.h (the same ones
// `ltmsim validate` uses).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "scene/SceneLoader.h"
#include "tests/SceneFixture.h"
#include "tests/Tolerances.h"
#include "trace/Tracer.h"
#include "validation/Validate.h"

using namespace ltm;

namespace {

using test::Built;

// A scene and its solid (tests/SceneFixture.h), messages naming "thin.yaml".
Built build(const std::string& yaml) { return test::build(yaml, "thin.yaml"); }

void expect_validates(const Built& b, const std::string& what) {
    for (auto rep : {Representation::Refined, Representation::Analytic}) {
        const validation::ValidationReport r = validation::validate(b.scene, b.solid, rep, 1);
        EXPECT_TRUE(r.passed()) << what << " (" << to_string(rep) << ")\n" << validation::format_report(r, true);
        EXPECT_GT(r.total.compared, 150) << what;
    }
}

}  // namespace

TEST(Thin, BubbleOneMicronUnderTheFront) {
    // Front vertex at z = -3; a bubble of radius 0.1 centred at z = -3 + 0.101 leaves 1 um of
    // glass over it. Axial rays through it must enter the glass, then the bubble, in that order.
    const Built b = build(R"(
object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
defects:
  - {type: bubble, center: [0.0, 0.0, -2.899], radius: 0.1}
)");
    const Tracer t(b.scene, b.solid);
    for (double x : {0.0, 0.03, -0.05, 0.07}) {
        const PrincipalPath p = t.principal_path({x, 0.0, -10}, {0, 0, 1});
        ASSERT_GE(p.tags.size(), 3u) << x;
        EXPECT_EQ(b.solid.surfaces[p.tags[0]].name, "front");
        EXPECT_EQ(b.solid.surfaces[p.tags[1]].name, "bubble 0");
        // The glass between them: 1 um on the axis (the vertex at -3, the bubble's top at -2.999).
        if (x == 0.0) {
            // Each vertex of the axial ray carries only its own intersection (tol::single_intersection):
            // the front sphere (R = 50) from z = -10 (M = 57 + 50), the bubble (M = 7.2 + 0.1).
            EXPECT_NEAR(p.vertices[1].z - p.vertices[0].z, 1e-3,
                        tol::single_intersection(107.0) + tol::single_intersection(7.3) + 4 * tol::kEps * 3);
        }
    }
    expect_validates(b, "1 um under the surface");
}

TEST(Thin, TenMicronScratchIsSeen) {
    // A V scratch 10 um wide and 10 um deep across the flat front of a window: rays aimed into
    // it from the camera side meet its walls first; rays 20 um beside it meet the front face.
    const Built b = build(R"(
object: {type: window, thickness: 3.0, diameter: 25.0, ior: 1.5}
defects:
  - {type: scratch, surface: front, start: [0.0, -5.0], end: [0.0, 5.0], width: 0.01, depth: 0.01, profile: V}
)");
    const Tracer t(b.scene, b.solid);
    for (double x : {-0.004, -0.001, 0.0005, 0.003}) {
        const PrincipalPath p = t.principal_path({x, 1.0, -10}, {0, 0, 1});
        ASSERT_FALSE(p.tags.empty());
        const std::string first = b.solid.surfaces[p.tags[0]].name;
        EXPECT_TRUE(first == "scratch 0 wall+" || first == "scratch 0 wall-") << x << ": " << first;
        // The wall point lies below the face (z > -1.5) by at most the depth.
        EXPECT_GT(p.vertices[0].z, -1.5);
        EXPECT_LT(p.vertices[0].z, -1.5 + 0.01);
    }
    for (double x : {-0.02, 0.02}) {
        const PrincipalPath p = t.principal_path({x, 1.0, -10}, {0, 0, 1});
        ASSERT_FALSE(p.tags.empty());
        EXPECT_EQ(b.solid.surfaces[p.tags[0]].name, "front") << x;
        EXPECT_DOUBLE_EQ(p.vertices[0].z, -1.5);
    }
}

class Scaled : public ::testing::TestWithParam<std::tuple<int, double>> {};

TEST_P(Scaled, EveryLensKindValidatesFromMicronsToMetres) {
    // Each kind (as in tests/geometry_lens.cpp) with a bubble, every length scaled by s.
    const auto [kind, s] = GetParam();
    const double r[8][2] = {{50, -50}, {40, INFINITY}, {INFINITY, -40}, {30, 60}, {60, 30}, {INFINITY, 40}, {-40, 40},
                            {INFINITY, INFINITY}};
    const double t[8] = {6, 5, 5, 5, 4, 2, 2, 3};
    auto len = [&](double v) { return std::isinf(v) ? std::string("inf") : fmt::format("{:.17g}", v * s); };
    const std::string yaml = fmt::format(R"(
object: {{type: lens, r1: {}, r2: {}, center_thickness: {}, diameter: {}, ior: 1.5168}}
defects:
  - {{type: bubble, center: [{}, 0.0, 0.0], radius: {}}}
camera: {{resolution: [10, 10], size: [{}, {}], numerical_aperture: 0.01, samples_per_pixel: 4}}
display: {{resolution: [100, 100], size: [{}, {}], z: {}}}
mesh: {{chord_tolerance: {}}}
)",
                                         len(r[kind][0]), len(r[kind][1]), len(t[kind]), len(25), len(2), len(0.2),
                                         len(25), len(25), len(100), len(100), len(60), len(1e-3));
    expect_validates(build(yaml), fmt::format("kind {} at scale {}", kind, s));
}

INSTANTIATE_TEST_SUITE_P(Kinds, Scaled,
                         ::testing::Combine(::testing::Range(0, 8), ::testing::Values(1e-3, 1.0, 1e3)));
