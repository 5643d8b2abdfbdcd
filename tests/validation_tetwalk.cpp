// The tetrahedral tracer against closed forms and the GRIN reference: a linear-n window (the
// catenary, validation/GrinClosedForms.h) meshed by TetGen at three index tolerances converges as
// O(h^2), i.e. linearly in index_tolerance (h ~ sqrt(tolerance)); a smooth inclusion passes
// `validate` against GrinReference with the meshed-field tolerance of ValidationTolerance.h.
#include <gtest/gtest.h>

#include <cmath>
#include <fmt/format.h>

#include "tests/SceneFixture.h"
#include "trace/Tracer.h"
#include "validation/GrinClosedForms.h"
#include "validation/Validate.h"

using namespace ltm;

namespace {

// The mean display-hit error of axial rays on a 0.4 mm grid through a window of n = 1.5 + 0.05 x
// (thickness 4, diameter 12, display at z = 40), traced through the TetGen mesh at `tolerance`,
// against the exact catenary.
double catenary_error(double tolerance, size_t* tets) {
    const test::Built b = test::build(fmt::format(R"(
object: {{type: window, thickness: 4.0, diameter: 12.0, ior: 1.5, index_field: {{type: linear_n, gradient: [0.05, 0.0, 0.0]}}}}
display: {{resolution: [200, 200], size: [50.0, 50.0], z: 40.0}}
mesh: {{index_tolerance: {}}}
)",
                                                  tolerance));
    *tets = b.solid.regions.at(0).num_tets();
    TracerOptions o;
    o.representation = Representation::Analytic;
    const Tracer t(b.scene, b.solid, o);
    double sum = 0;
    int n = 0;
    for (int i = -10; i <= 10; ++i)
        for (int j = -10; j <= 10; ++j) {
            const double x = 0.4 * i + 0.0137, y = 0.4 * j + 0.0071;
            const PrincipalPath p = t.principal_path({x, y, -10}, {0, 0, 1});
            const auto c = validation::grin_closed_form::catenary_window(1.5, 0.05, 4.0, x, y, {0, 0, 1}, 40.0);
            EXPECT_TRUE(p.display_hit && c.display_hit) << x << " " << y;
            if (!p.display_hit || !c.display_hit) continue;
            sum += std::hypot(p.x - c.display_x, p.y - c.display_y);
            ++n;
        }
    return sum / n;
}

}  // namespace

TEST(TetWalkConvergence, CatenaryConvergesAsTheIndexTolerance) {
    // The path through n^2 interpolated linearly over tetrahedra of size h errs by O(h^2) on a
    // lattice mesh (geometry/TetMesh.h): the gradient errors O(h M) are periodic with zero mean and
    // cancel along the path. h ~ sqrt(tolerance), so the error is proportional to the tolerance:
    // over a factor 16 in tolerance the log-log slope is 1 (order 2 in h). The unstructured mesh's
    // random-walk order h^1.5 would give a slope of 0.75, first order in h 0.5: the band [0.85,
    // 1.15] (order 1.7..2.3 in h) admits second order with the third-order terms and the finite
    // sample (441 rays) of two coarse levels, and rejects both.
    size_t t1 = 0, t2 = 0, t3 = 0;
    const double e1 = catenary_error(4e-3, &t1), e2 = catenary_error(1e-3, &t2), e3 = catenary_error(2.5e-4, &t3);
    EXPECT_GT(e1, e2);
    EXPECT_GT(e2, e3);
    const double slope = std::log(e1 / e3) / std::log(16.0);
    EXPECT_GT(slope, 0.85) << e1 << " " << e2 << " " << e3;
    EXPECT_LT(slope, 1.15) << e1 << " " << e2 << " " << e3;
    // More tetrahedra at the finer tolerances, about (16)^1.5 = 64 times over the two steps.
    EXPECT_GT(t3, 8 * t1);
}

TEST(TetWalkConvergence, SmoothInclusionValidatesWithinTheMeshedBound) {
    const test::Built b = test::build(R"(
object: {type: window, thickness: 8.0, diameter: 30.0, ior: 1.5}
defects:
  - {type: inhomogeneity, center: [0.0, 0.0, 0.0], radius: 2.5, delta_n: 0.02, profile: smooth}
display: {resolution: [500, 500], size: [100.0, 100.0], z: 60.0}
mesh: {index_tolerance: 1e-3}
)");
    const validation::ValidationReport r = validation::validate(b.scene, b.solid, Representation::Analytic, 1);
    EXPECT_TRUE(r.passed()) << validation::format_report(r, true);
    EXPECT_GT(r.total.compared, 150);
}
