// The tetrahedral tracer against closed forms and the GRIN reference: a linear-n window (the
// catenary, validation/GrinClosedForms.h) meshed by TetGen at three index tolerances converges as
// O(h^2), i.e. linearly in index_tolerance (h ~ sqrt(tolerance)); a smooth inclusion passes
// `validate` against GrinReference with the meshed-field tolerance of ValidationTolerance.h.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>
#include <fmt/format.h>

#include <array>
#include <random>

#include "geometry/TetMesh.h"
#include "tests/SceneFixture.h"
#include "tests/Tolerances.h"
#include "trace/Tracer.h"
#include "validation/GrinClosedForms.h"
#include "validation/GrinReference.h"
#include "validation/Validate.h"

using namespace ltm;

namespace {

// The mean display-hit errors of axial rays on a 0.4 mm grid through a window of n = 1.5 + 0.05 x
// (thickness 4, diameter 12, display at z = 40), traced through the TetGen mesh at `tolerance`,
// against the exact catenary: with the lattice's end correction (geometry/LatticePhase.h), and
// without it (the mesh's Hessian removed, so that paths are handed over uncorrected).
struct CatenaryErrors {
    double corrected = 0, plain = 0;
    size_t tets = 0;
};
CatenaryErrors catenary_errors(double tolerance) {
    test::Built b = test::build(fmt::format(R"(
object: {{type: window, thickness: 4.0, diameter: 12.0, ior: 1.5, index_field: {{type: linear_n, gradient: [0.05, 0.0, 0.0]}}}}
display: {{resolution: [200, 200], size: [50.0, 50.0], z: 40.0}}
mesh: {{index_tolerance: {}}}
)",
                                            tolerance));
    CatenaryErrors out;
    out.tets = b.solid.regions.at(0).num_tets();
    EXPECT_GT(b.solid.regions.at(0).lattice.spacing, 0);
    for (bool plain : {false, true}) {
        if (plain) b.solid.regions.at(0).hessian = nullptr;
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
        (plain ? out.plain : out.corrected) = sum / n;
    }
    return out;
}

// The least-squares slope of log y against log x.
double log_log_slope(const std::vector<double>& x, const std::vector<double>& y) {
    double mx = 0, my = 0;
    for (size_t i = 0; i < x.size(); ++i) mx += std::log(x[i]) / x.size(), my += std::log(y[i]) / y.size();
    double sxy = 0, sxx = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        sxy += (std::log(x[i]) - mx) * (std::log(y[i]) - my);
        sxx += (std::log(x[i]) - mx) * (std::log(x[i]) - mx);
    }
    return sxy / sxx;
}

}  // namespace

TEST(TetWalkConvergence, CatenaryConvergesAsTheIndexTolerance) {
    // The path through n^2 interpolated linearly over tetrahedra of size h errs by O(h^2) on a
    // lattice mesh (geometry/TetMesh.h): the gradient errors O(h M) are periodic with zero mean and
    // cancel along the path. h ~ sqrt(tolerance), so the error is proportional to the tolerance:
    // the log-log slope in tolerance is 1 (order 2 in h). The unstructured mesh's random-walk
    // order h^1.5 would give a slope of 0.75, first order in h 0.5: the band [0.85, 1.15] (order
    // 1.7..2.3 in h) admits second order with the third-order terms and the finite sample (441
    // rays), and rejects both. What is left after the cancellation is the periodic error's value
    // where a path enters and leaves the lattice (the window's faces), in a phase that changes
    // from level to level, so single levels scatter about the power law by up to a factor 2:
    // the slope is the least-squares fit over six levels, a factor 32 in tolerance. The
    // coarsest, 2e-3, already has cells (1.4 mm) smaller than the window's thickness (4 mm).
    //
    // That end term is what the lattice's end correction removes (geometry/LatticePhase.h): it
    // is exact for this field (n^2 quadratic, H constant), so what the corrected walk leaves is
    // of higher order, and it must be well below the plain walk's error at every level. If Psi
    // were off by a factor c, the end term would be left at |1 - c| of its size: a third or less
    // holds c within [2/3, 4/3] (a wrong sign would double the error). The corrected error still
    // converges at least as the plain one does (slope above the band's lower end).
    std::vector<double> tolerance, plain, corrected;
    std::vector<size_t> tets;
    for (int i = 0; i < 6; ++i) {
        tolerance.push_back(2e-3 / std::pow(2.0, i));
        const CatenaryErrors e = catenary_errors(tolerance.back());
        plain.push_back(e.plain);
        corrected.push_back(e.corrected);
        tets.push_back(e.tets);
    }
    std::string levels;
    for (int i = 0; i < 6; ++i) levels += fmt::format(" {:.3g}:{:.3g}/{:.3g}", tolerance[i], plain[i], corrected[i]);
    const double slope = log_log_slope(tolerance, plain);
    EXPECT_GT(slope, 0.85) << levels;
    EXPECT_LT(slope, 1.15) << levels;
    EXPECT_GT(plain.front(), plain.back()) << levels;
    for (int i = 0; i < 6; ++i) EXPECT_LT(corrected[i], plain[i] / 3) << levels;
    EXPECT_GT(log_log_slope(tolerance, corrected), 0.85) << levels;
    // More tetrahedra at the finer tolerances, about 32^1.5 = 181 times over the five steps.
    EXPECT_GT(tets.back(), 60 * tets.front());
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

namespace {

// The 2.5 mm, delta_n = 0.02 smooth inclusion of bench/bench_grin.cpp (section e), meshed at
// `tolerance`.
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

// The smooth profile (docs/conventions.md), written out here: n = 1.5 + 0.02 (1 - r^2 / R^2)^2
// for r < R = 2.5, squared.
double profile_n2(const Vec3& x) {
    const double s = length2(x) / (2.5 * 2.5);
    const double n = s < 1 ? 1.5 + 0.02 * (1 - s) * (1 - s) : 1.5;
    return n * n;
}

}  // namespace

// The inclusion's mesh does not store the field at its vertices (defects/SolidBuilder.cpp: the
// profile's polynomial continued past the ellipsoid, less the lattice's mean interpolation error),
// but what paths see of it, n^2 interpolated inside the ellipsoid, is still within the tolerance of
// the field: at the centre of every tetrahedron's enclosing ball and at four random points of
// each, wherever they lie inside the ellipsoid.
TEST(TetWalkInclusion, InterpolatedFieldIsWithinTheToleranceInsideTheEllipsoid) {
    const double tolerance = 1e-3;
    const test::Built b = test::build(inclusion_scene(tolerance));
    const TetMesh& m = b.solid.regions.at(0);
    // |grad n^2| = 2 n 0.02 |d(1 - s)^2 / dx| <= 2 (1.52) 0.02 (4 / 2.5) max sqrt(s) (1 - s) <= 0.04
    const double slack = tol::interpolation_rounding(1.52 * 1.52, 2.5, 0.04);
    std::mt19937_64 rng(5);
    std::exponential_distribution<double> e(1.0);
    size_t checked = 0, above = 0;
    double worst = 0;
    for (size_t t = 0; t < m.tets.size(); ++t) {
        const auto& v = m.tets[t];
        const Vec3 p[4] = {m.vertices[v[0]], m.vertices[v[1]], m.vertices[v[2]], m.vertices[v[3]]};
        auto check = [&](const std::array<double, 4>& l) {
            const Vec3 x = p[0] * l[0] + p[1] * l[1] + p[2] * l[2] + p[3] * l[3];
            if (!(length2(x) < 2.5 * 2.5)) return;
            const double interpolated = l[0] * m.n2[v[0]] + l[1] * m.n2[v[1]] + l[2] * m.n2[v[2]] + l[3] * m.n2[v[3]];
            const double err = std::fabs(interpolated - profile_n2(x));
            worst = std::max(worst, err);
            ++checked;
            if (err > tolerance + slack) ++above;
        };
        Vec3 c;
        smallest_enclosing_ball(p[0], p[1], p[2], p[3], &c);
        // c's barycentric coordinates (it lies in the tetrahedron, tests/geometry_tetmesh.cpp)
        auto det = [](const Vec3& a, const Vec3& b2, const Vec3& c2, const Vec3& d) { return dot(b2 - a, cross(c2 - a, d - a)); };
        const double D = det(p[0], p[1], p[2], p[3]);
        std::array<double, 4> l{};
        for (int i = 0; i < 4; ++i) {
            Vec3 q[4] = {p[0], p[1], p[2], p[3]};
            q[i] = c;
            l[i] = det(q[0], q[1], q[2], q[3]) / D;
        }
        check(l);
        for (int k = 0; k < 4; ++k) {
            double sum = 0;
            for (double& x : l) sum += (x = e(rng));
            for (double& x : l) x /= sum;
            check(l);
        }
    }
    EXPECT_GT(checked, 100000u);
    EXPECT_EQ(above, 0u) << "largest error " << worst;
}

// The lattice's mean interpolation error, a smooth bias field a^2 tr(D^2 n^2) / 24, bends every
// path the same way: without its correction the display hits of the rays through the inclusion
// erred outward (the bias grows from the centre, where tr D^2 n^2 < 0, to the shell, where it is
// > 0) by nearly their whole error (mean signed radial error 0.96 of the mean error at this
// tolerance, 46 standard errors). With it, what is left is the periodic part, whose phase differs
// from ray to ray: the signed radial errors of the 300-odd rays inside rho < 0.9 average to zero
// within their standard error. A Z-test at 4 standard errors (a false alarm for a zero mean once
// in 16,000 runs; the test is deterministic, so once the lattice's phase passes, it passes).
TEST(TetWalkInclusion, DisplayErrorsHaveNoSystematicRadialPart) {
    const test::Built b = test::build(inclusion_scene(1e-3));
    TracerOptions o;
    o.representation = Representation::Analytic;
    const Tracer t(b.scene, b.solid, o);
    const validation::GrinReference reference(b.scene);
    std::vector<double> radial;
    double sum_abs = 0;
    for (int i = -12; i <= 12; ++i)
        for (int j = -12; j <= 12; ++j) {
            const double x = 0.2 * i + 0.013, y = 0.2 * j + 0.007, r = std::hypot(x, y);
            if (r > 0.9 * 2.5) continue;
            const validation::Path p = reference.principal_path({x, y, -10}, {0, 0, 1});
            const PrincipalPath q = t.principal_path({x, y, -10}, {0, 0, 1});
            ASSERT_TRUE(p.display_hit && q.display_hit) << x << " " << y;
            radial.push_back(((q.x - p.display_x) * x + (q.y - p.display_y) * y) / r);
            sum_abs += std::hypot(q.x - p.display_x, q.y - p.display_y);
        }
    const double n = static_cast<double>(radial.size());
    const double mean = std::accumulate(radial.begin(), radial.end(), 0.0) / n;
    double var = 0;
    for (double v : radial) var += (v - mean) * (v - mean);
    const double standard_error = std::sqrt(var / (n - 1) / n);
    EXPECT_GT(n, 300);
    EXPECT_LT(std::fabs(mean), 4 * standard_error)
        << "mean signed radial error " << mean << " mm, mean error " << sum_abs / n << " mm, standard error "
        << standard_error;
}

// The target for a smooth inclusion at the default meshing (MeshOptions' index_tolerance): the
// 2.5 mm, delta_n = 0.02 inclusion in the 8 mm window, display 60 mm behind, every display hit of
// the 625 axial rays of bench/bench_grin.cpp (section e) within tol::kInclusionDisplayTarget of
// the converged reference (GrinReference, integrated to 1e-12 per step: its own error is orders
// below). Without the lattice's end correction the largest error is 1.6e-3 mm
// (docs/grin.md), most of it the end term the correction removes.
TEST(TetWalkInclusion, DisplayHitsMeetTheTargetAtTheDefaultTolerance) {
    const double tolerance = MeshOptions{}.index_tolerance;
    const test::Built b = test::build(inclusion_scene(tolerance));
    TracerOptions o;
    o.representation = Representation::Analytic;
    const Tracer t(b.scene, b.solid, o);
    const validation::GrinReference reference(b.scene);
    double worst = 0;
    int n = 0;
    for (int i = -12; i <= 12; ++i)
        for (int j = -12; j <= 12; ++j) {
            const double x = 0.2 * i + 0.013, y = 0.2 * j + 0.007;
            const validation::Path p = reference.principal_path({x, y, -10}, {0, 0, 1});
            const PrincipalPath q = t.principal_path({x, y, -10}, {0, 0, 1});
            ASSERT_TRUE(p.display_hit && q.display_hit) << x << " " << y;
            const double e = std::hypot(q.x - p.display_x, q.y - p.display_y);
            EXPECT_LT(e, tol::kInclusionDisplayTarget) << "ray at " << x << " " << y;
            worst = std::max(worst, e);
            ++n;
        }
    EXPECT_EQ(n, 625);
    std::printf("largest display error %.3g mm over %d rays, %zu tetrahedra\n", worst, n, b.solid.regions.at(0).num_tets());
}
