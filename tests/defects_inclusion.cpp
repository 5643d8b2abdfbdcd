// The smooth inclusion's field as the mesh uses it (defects/Inclusion.h): the continued
// polynomial's Hessian, which the lattice's end correction reads (geometry/LatticePhase.h),
// against central differences of the field itself, its trace against the Laplacian, and its norm
// within the curvature bound that the refinement criterion relies on.
#include "defects/Inclusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tests/Tolerances.h"

using namespace ltm;

namespace {

// An elongated, turned inclusion (semi-axes 0.8, 1.3, 2.1 mm), delta_n = 0.02 in n = 1.5.
Defect turned_inclusion() {
    Defect d;
    d.type = DefectType::Inhomogeneity;
    d.center = {0.4, -0.3, 0.7};
    d.semi_axes = {0.8, 1.3, 2.1};
    d.frame = rotation_from_euler_deg({20.0, -35.0, 50.0});
    d.delta_n = 0.02;
    d.index_profile = IndexProfile::Smooth;
    return d;
}

// Random points at s in (0, s_ext): inside the ellipsoid and in the continued shell beyond.
template <class F>
void at_random_points(const Defect& d, double s_ext, F&& f) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int n = 0;
    while (n < 300) {
        const Vec3 y{u(rng), u(rng), u(rng)};
        const double s = length2(y) * s_ext;
        if (!(s < s_ext) || s < 1e-3) continue;
        const Vec3 b = y * std::sqrt(s_ext);
        const Vec3 x = d.center + d.frame * Vec3{b.x * d.semi_axes.x, b.y * d.semi_axes.y, b.z * d.semi_axes.z};
        f(x);
        ++n;
    }
}

}  // namespace

TEST(InclusionField, ExtendedHessianIsTheFieldsSecondDerivative) {
    const Defect d = turned_inclusion();
    const InclusionField f(d, 1.5);
    const double s_ext = 1.2;
    const double step = tol::kFieldDifferenceStep * f.min_semi_axis();
    const double bound = f.extended_hessian_bound(d.center, std::sqrt(s_ext) * f.max_semi_axis(), s_ext);
    at_random_points(d, s_ext, [&](const Vec3& x) {
        const Mat3 h = f.extended_hessian_n2(x, s_ext);
        double lap = 0;
        for (int i = 0; i < 3; ++i) {
            lap += h(i, i);
            for (int j = 0; j < 3; ++j) {
                Vec3 ei, ej;
                ei[i] = step;
                ej[j] = step;
                const double fd = (f.extended_n2(x + ei + ej, s_ext) - f.extended_n2(x + ei - ej, s_ext) -
                                   f.extended_n2(x - ei + ej, s_ext) + f.extended_n2(x - ei - ej, s_ext)) /
                                  (4.0 * step * step);
                EXPECT_NEAR(h(i, j), fd, tol::kFieldDifferenceRelative * bound) << i << j;
            }
        }
        EXPECT_NEAR(lap, f.extended_laplacian_n2(x, s_ext), tol::kFieldIdentityRelative * bound);
        // Any |v^T H v| over unit v is at most the spectral norm, which the criterion's bound at
        // the point (radius 0) must hold inside the ellipsoid (outside, where no path uses the
        // mesh, the bound is 0 by design).
        if (!f.inside(x)) return;
        const double at_point = f.extended_hessian_bound(x, 0.0, s_ext);
        for (const Vec3& v : {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}, normalize(Vec3{1, 1, 1}),
                              normalize(Vec3{1, -2, 0.5}), normalize(x - d.center)})
            EXPECT_LE(std::fabs(dot(v, h * v)), at_point * (1 + tol::kFieldIdentityRelative));
    });
    // Beyond s_ext the mesh holds the glass's index: no curvature.
    const Vec3 far = d.center + d.frame * Vec3{0, 0, 1.2 * d.semi_axes.z};
    const Mat3 h = f.extended_hessian_n2(far, s_ext);
    for (double v : h.m) EXPECT_EQ(v, 0.0);
}
