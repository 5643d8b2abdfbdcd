// Closed-form graded-index paths (trace/GrinPath.h) through the tracer, against closed forms
// derived here: the Luneburg sphere, a GRIN rod and a linear gradient, at the double-precision
// floor (tests/Tolerances.h, grin_closed_form); arc lengths for Beer-Lambert; the invariant
// |p| = n; and no TetGen for any of them.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tests/SceneFixture.h"
#include "tests/Tolerances.h"
#include "trace/GrinPath.h"
#include "trace/Tracer.h"

using namespace ltm;

namespace {

constexpr double kU = 0x1p-53;

// A Luneburg sphere of radius 10: n^2 = 2 (1 - |x|^2 / (2 R^2)), i.e. ior = sqrt 2 and
// g = 1 / (R sqrt 2) (docs/conventions.md).
const char* kLuneburg = R"(
object:
  type: sphere
  radius: 10.0
  ior: 1.4142135623730951
  index_field: {type: spherical_n2, g: 0.0707106781186548}
display: {resolution: [100, 100], size: [100.0, 100.0], z: 60.0}
)";

}  // namespace

TEST(Grin, LuneburgFocusesEveryParallelBeamOnTheFarSide) {
    // Luneburg (1944): with n^2 = 2 - |x|^2 / R^2, the ray equation d^2 r / dtau^2 = -r / R^2 gives
    // r(tau) = r0 cos(tau / R) + R p0 sin(tau / R); a ray entering at r0 (|r0| = R, n = 1 there,
    // so unrefracted: p0 = d0) is on the sphere again when |r|^2 = R^2, i.e. 2 R (r0 . d0)
    // sin cos = 0, at tau = pi R / 2: there r = R d0. Every ray of direction d0 leaves at R d0.
    const test::Built b = test::build(kLuneburg);
    const Tracer t(b.scene, b.solid);
    std::mt19937_64 gen(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const double R = 10.0, L = 60.0 + R;
    for (int k = 0; k < 200; ++k) {
        Vec3 d0;
        do d0 = {u(gen), u(gen), u(gen)}; while (length(d0) > 1 || length(d0) < 0.1);
        d0 = normalize(d0);
        // An entry point on the sphere's hemisphere facing the ray, from outside.
        Vec3 b1, b2;
        orthonormal_basis(d0, b1, b2);
        const double rho = 0.95 * R * std::sqrt(0.5 + 0.5 * u(gen)), phi = 3.14159 * u(gen);
        const Vec3 origin = (b1 * std::cos(phi) + b2 * std::sin(phi)) * rho - d0 * (2 * R);
        const PrincipalPath p = t.principal_path(origin, d0);
        ASSERT_EQ(p.vertices.size(), 2u) << k;
        EXPECT_LT(distance(p.vertices[1], d0 * R), tol::grin_closed_form(2, L, 1.0)) << k;
    }
}

TEST(Grin, RodPathIsSinusoidal) {
    // A window of thickness t with n^2 = n0^2 (1 - G^2 (x^2 + y^2)). A ray parallel to the axis at
    // height x0 enters the flat front unrefracted with p0 = (0, 0, n(x0)); in the glass
    // dp/dtau = -n0^2 G^2 (x, y, 0), so x(tau) = x0 cos(w tau) with w = n0 G, z = -t/2 + n(x0) tau:
    // it reaches the back face at tau_e = t / n(x0), at x_e = x0 cos(w tau_e), with
    // p_x = -x0 w sin(w tau_e). The flat back face conserves the tangential momentum, so in air
    // sin(theta) = p_x and the display hit is x_e + tan(theta) (Z - t/2).
    const test::Built b = test::build(R"(
object:
  type: window
  thickness: 20.0
  diameter: 10.0
  ior: 1.6
  index_field: {type: radial_n2, g: 0.08}
display: {resolution: [100, 100], size: [200.0, 200.0], z: 60.0}
)");
    const Tracer t(b.scene, b.solid);
    const double n0 = 1.6, G = 0.08, th = 20.0, Z = 60.0, L = Z + 10 + th;
    const double w = n0 * G;
    auto closed = [&](double x0, double& xe, double& xd) {
        const double nx = n0 * std::sqrt(1 - G * G * x0 * x0);
        const double te = th / nx;
        xe = x0 * std::cos(w * te);
        const double px = -x0 * w * std::sin(w * te);
        xd = xe + px / std::sqrt(1 - px * px) * (Z - th / 2);
    };
    for (double x0 : {0.1, 0.5, 1.0, 2.0, -3.0, 4.5}) {
        const PrincipalPath p = t.principal_path({x0, 0, -20}, {0, 0, 1});
        ASSERT_EQ(p.vertices.size(), 2u);
        ASSERT_TRUE(p.display_hit);
        double xe, xd;
        closed(x0, xe, xd);
        // The display hit's sensitivity to x0, from the closed form by central differences.
        double a, xp, xm;
        closed(x0 + 1e-6, a, xp);
        closed(x0 - 1e-6, a, xm);
        const double kappa = std::fabs(xp - xm) / 2e-6;
        EXPECT_NEAR(p.vertices[1].x, xe, tol::grin_closed_form(1, L, kappa)) << x0;
        EXPECT_NEAR(p.vertices[1].z, th / 2, tol::grin_closed_form(1, L, kappa)) << x0;
        EXPECT_NEAR(p.x, xd, tol::grin_closed_form(2, L, kappa)) << x0;
        EXPECT_NEAR(p.y, 0.0, tol::grin_closed_form(2, L, kappa)) << x0;
    }
}

TEST(Grin, LinearGradientPathIsAParabola) {
    // n^2 = n0^2 + g x in a window: entering at normal incidence at x0, p0 = (0, 0, n(x0)); with
    // dp/dtau = (g / 2, 0, 0) the path is x = x0 + g tau^2 / 4, z = -t/2 + n(x0) tau, leaving at
    // tau_e = t / n(x0) with p_x = g tau_e / 2; in air sin(theta) = p_x.
    const test::Built b = test::build(R"(
object:
  type: window
  thickness: 8.0
  diameter: 30.0
  ior: 1.5
  index_field: {type: linear_n2, gradient: [0.01, 0.0, 0.0]}
display: {resolution: [100, 100], size: [100.0, 100.0], z: 60.0}
)");
    const Tracer t(b.scene, b.solid);
    const double n0 = 1.5, g = 0.01, th = 8.0, Z = 60.0, L = Z + 30 + th;
    for (double x0 : {-10.0, -2.0, 0.0, 3.0, 9.0}) {
        const PrincipalPath p = t.principal_path({x0, 0, -20}, {0, 0, 1});
        ASSERT_EQ(p.vertices.size(), 2u);
        const double nx = std::sqrt(n0 * n0 + g * x0), te = th / nx;
        const double xe = x0 + g * te * te / 4, px = g * te / 2;
        const double xd = xe + px / std::sqrt(1 - px * px) * (Z - th / 2);
        // d(display)/d(x0) = 1 + O(g): kappa <= 2.
        EXPECT_NEAR(p.vertices[1].x, xe, tol::grin_closed_form(1, L, 2.0)) << x0;
        EXPECT_NEAR(p.x, xd, tol::grin_closed_form(2, L, 2.0)) << x0;
    }
}

TEST(Grin, ArcLengthOfTheParabolaMatchesItsClosedForm) {
    // |p(tau)| = |p0 + b tau / 2| = sqrt(A + B tau + C tau^2) with A = |p0|^2, B = p0 . b,
    // C = |b|^2 / 4. Its integral (Gradshteyn & Ryzhik 2.262.1): with q = 4 A C - B^2 > 0 and
    // X = A + B tau + C tau^2,
    //   S = ((2 C tau + B) sqrt(X) - B sqrt(A)) / (4 C)
    //       + q / (8 C^1.5) ln((2 sqrt(C X) + 2 C tau + B) / (2 sqrt(C A) + B)).
    QuadraticForm q;
    q.c = 2.25;
    q.b = {0.3, -0.1, 0.05};
    const GrinField f(q, 3.0, 10.0);
    const Vec3 p0{0.2, 0.1, 1.45};
    const GrinPath path(f, {0, 0, 0}, p0);
    for (double tau : {0.5, 3.0, 7.0}) {
        const double A = length2(p0), B = dot(p0, q.b), C = length2(q.b) / 4;
        const double X = A + B * tau + C * tau * tau, Q = 4 * A * C - B * B;
        const double S = ((2 * C * tau + B) * std::sqrt(X) - B * std::sqrt(A)) / (4 * C) +
                         Q / (8 * std::pow(C, 1.5)) *
                             std::log((2 * std::sqrt(C * X) + 2 * C * tau + B) / (2 * std::sqrt(C * A) + B));
        // The quadrature is refined to 1e-12 relative (GrinPath.h); the closed form's own
        // rounding is ~1e-14 relative.
        EXPECT_NEAR(path.arc_length(tau), S, tol::kGrinArcLengthRelative * S) << tau;
    }
}

TEST(Grin, MomentumStaysOnTheIndexSurface) {
    // |p|^2 - n^2(r) is the Hamiltonian of the ray equation, 0 on a ray and conserved along the
    // closed form: after a quarter period of a general quadratic field it is still ~u n^2.
    QuadraticForm q;
    q.c = 2.4;
    q.b = {0.02, -0.01, 0.03};
    q.H = Mat3{{-0.04, 0.01, 0.0, 0.01, -0.03, 0.005, 0.0, 0.005, 0.01}};
    const GrinField f(q, 2.6, 5.0);
    const Vec3 r0{0.5, -0.3, 0.2};
    const Vec3 d = normalize(Vec3{0.3, 0.2, 1.0});
    const GrinPath path(f, r0, d * std::sqrt(q(r0)));
    for (double tau : {0.1, 1.0, 3.0, 6.0}) {
        Vec3 r, p;
        path.state(tau, r, p);
        EXPECT_LT(std::fabs(length2(p) - q(r)), 64 * kU * 2.6) << tau;
    }
}

TEST(Grin, ClosedFormFieldsRunNoTetGen) {
    const test::Built b = test::build(kLuneburg);
    EXPECT_TRUE(b.solid.regions.empty());
}
