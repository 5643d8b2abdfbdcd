// Interface optics and exact intersections against closed forms (Hecht, Optics, 5th ed., 4.6).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "tests/Tolerances.h"
#include "trace/Intersect.h"
#include "trace/Optics.h"
#include "trace/SinCos.h"

using namespace ltm;

TEST(Fresnel, NormalIncidence) {
    // R = ((n1 - n2) / (n1 + n2))^2 = 0.04 for air -> glass of index 1.5, from either side.
    EXPECT_NEAR(fresnel(1.0, 1.0 / 1.5).reflectance, 0.04, 8 * tol::kEps);
    EXPECT_NEAR(fresnel(1.0, 1.5).reflectance, 0.04, 8 * tol::kEps);
}

TEST(Fresnel, BrewsterAngleHasNoPPolarisedReflection) {
    // At tan(theta_B) = n2 / n1, rp = 0, so R = Rs / 2 with rs = (cos_i - n cos_t) / (cos_i + n cos_t)
    // and cos_t = sin(theta_B) (the reflected and refracted rays are perpendicular).
    const double n = 1.5, tb = std::atan(n);
    const double ci = std::cos(tb), ct = std::sin(tb);
    const double rs = (ci - n * ct) / (ci + n * ct);
    EXPECT_NEAR(fresnel(ci, 1.0 / n).reflectance, 0.5 * rs * rs, 16 * tol::kEps);
}

TEST(Fresnel, TotalInternalReflectionBeyondTheCriticalAngle) {
    const double n = 1.5, crit = std::asin(1.0 / n);
    EXPECT_FALSE(fresnel(std::cos(crit - 1e-6), n).total_internal_reflection);
    const FresnelResult f = fresnel(std::cos(crit + 1e-6), n);
    EXPECT_TRUE(f.total_internal_reflection);
    EXPECT_EQ(f.reflectance, 1.0);
    // Just below the critical angle the transmitted ray grazes: R -> 1.
    EXPECT_GT(fresnel(std::cos(crit - 1e-9), n).reflectance, 0.99);
}

TEST(Snell, VectorRefractionSatisfiesSnellsLaw) {
    // n1 sin(theta_i) = n2 sin(theta_t), t unit and coplanar with d and n, for random directions.
    std::mt19937_64 g(3);
    std::normal_distribution<double> u;
    for (int i = 0; i < 1000; ++i) {
        const Vec3 n = normalize(Vec3{u(g), u(g), u(g)});
        Vec3 d = normalize(Vec3{u(g), u(g), u(g)});
        if (dot(d, n) > 0) d = -d;
        for (double eta : {1.0 / 1.5168, 1.5168, 1.0 / 1.0003}) {
            const double ci = -dot(d, n);
            const FresnelResult f = fresnel(ci, eta);
            if (f.total_internal_reflection) continue;
            const Vec3 t = refract(d, n, eta, ci, f.cos_t);
            EXPECT_NEAR(length(t), 1.0, 8 * tol::kEps);
            const double sin_i = length(cross(d, n)), sin_t = length(cross(t, n));
            EXPECT_NEAR(eta * sin_i, sin_t, 16 * tol::kEps);
            EXPECT_NEAR(dot(cross(d, n), t), 0.0, 16 * tol::kEps);  // coplanar
            EXPECT_LT(dot(t, n), 0.0);                               // continues through
        }
    }
}

TEST(Intersect, SphereRootsAndTheStableQuadratic) {
    // A ray along +z through a sphere of radius 2 centred at (0, 0, 10): roots 8 and 12.
    Roots r = intersect(Surface::sphere({0, 0, 10}, 2.0), {0, 0, 0}, {0, 0, 1});
    ASSERT_EQ(r.count, 2);
    EXPECT_DOUBLE_EQ(r.t[0], 8.0);
    EXPECT_DOUBLE_EQ(r.t[1], 12.0);
    // Far origin, tiny sphere: the textbook (-b +- sqrt(disc)) / 2a loses the near root's digits to
    // cancellation; the stable form keeps both to a few ulps: roots 1e6 -+ 1e-6.
    r = intersect(Surface::sphere({0, 0, 1e6}, 1e-6), {0, 0, 0}, {0, 0, 1});
    ASSERT_EQ(r.count, 2);
    EXPECT_NEAR(r.t[0], 1e6 - 1e-6, 4 * tol::kEps * 1e6);
    EXPECT_NEAR(r.t[1], 1e6 + 1e-6, 4 * tol::kEps * 1e6);
    // Offset ray at distance h from the centre: roots 10 -+ sqrt(4 - h^2).
    const double h = 1.999999;
    r = intersect(Surface::sphere({0, 0, 10}, 2.0), {h, 0, 0}, {0, 0, 1});
    ASSERT_EQ(r.count, 2);
    EXPECT_NEAR(r.t[1] - r.t[0], 2 * std::sqrt((2 - h) * (2 + h)),
                2 * tol::single_intersection(std::hypot(h, 10.0) + 2.0));  // two roots
    // Missing ray.
    EXPECT_EQ(intersect(Surface::sphere({0, 0, 10}, 2.0), {2.1, 0, 0}, {0, 0, 1}).count, 0);
}

TEST(Intersect, PlaneCylinderConeTorusEllipsoid) {
    Roots r = intersect(Surface::plane({0, 0, 5}, {0, 0, -1}), {1, 2, 0}, normalize(Vec3{0, 3, 4}));
    ASSERT_EQ(r.count, 1);
    EXPECT_NEAR(r.t[0], 25.0 / 4.0, tol::plane_root(25.0 / 4.0));  // z = 4 t / 5 = 5
    r = intersect(Surface::cylinder({0, 0, 0}, {0, 0, 1}, 3.0), {-10, 0, 7}, {1, 0, 0});
    ASSERT_EQ(r.count, 2);
    EXPECT_DOUBLE_EQ(r.t[0], 7.0);
    EXPECT_DOUBLE_EQ(r.t[1], 13.0);
    // Cone with apex at the origin, half-angle 45 deg, axis z: the line x = 1, along z meets it at z = -+1.
    r = intersect(Surface::cone({0, 0, 0}, {0, 0, 1}, kPi / 4), {1, 0, -5}, {0, 0, 1});
    ASSERT_EQ(r.count, 2);
    // 0.5 t^2 - 5 t + 12 = 0 (M = |o| = sqrt 26, D = 1).
    EXPECT_NEAR(r.t[0], 4.0, tol::quadratic_root(4.0, std::sqrt(26.0), 1.0));
    EXPECT_NEAR(r.t[1], 6.0, tol::quadratic_root(6.0, std::sqrt(26.0), 1.0));
    // Torus R = 3, r = 1 about z: the x axis crosses it at x = -4, -2, 2, 4.
    r = intersect(Surface::torus({0, 0, 0}, {0, 0, 1}, 3.0, 1.0), {-10, 0, 0}, {1, 0, 0});
    ASSERT_EQ(r.count, 4);
    const double expected[4] = {6, 8, 12, 14};
    // s = t - 10 solves s^4 - 20 s^2 + 64 = 0 (exact integer coefficients), then t = s + 10.
    for (int i = 0; i < 4; ++i) {
        const double s = expected[i] - 10, abs_sum = 64 + 20 * s * s + s * s * s * s, slope = 4 * s * s * s - 40 * s;
        EXPECT_NEAR(r.t[i], expected[i], tol::poly_root(4, abs_sum, slope) + 2 * tol::kEps * 14);
    }
    // Ellipsoid with semi-axes (4, 2, 1), rotated 90 deg about z (its long axis along y).
    r = intersect(Surface::ellipsoid({0, 0, 0}, rotation_from_euler_deg({0, 0, 90}), {4, 2, 1}), {0, -10, 0}, {0, 1, 0});
    ASSERT_EQ(r.count, 2);
    // In the unit-sphere frame: a root of a sphere hit from |o - c| = 10 with semi-axes <= 4.
    EXPECT_NEAR(r.t[0], 6.0, tol::single_intersection(10.0 + 4.0));
    EXPECT_NEAR(r.t[1], 14.0, tol::single_intersection(10.0 + 4.0));
}

TEST(Intersect, ErrorBoundCoversTheComputedPoint) {
    // Spawning a ray from p moved by the bound along the normal must put it strictly on one side.
    std::mt19937_64 g(11);
    std::uniform_real_distribution<double> u(-1, 1);
    for (double scale : {1e-3, 1.0, 1e3}) {
        const Surface s = Surface::sphere({0.3 * scale, -0.2 * scale, 5 * scale}, 2 * scale);
        for (int i = 0; i < 2000; ++i) {
            const Vec3 o{u(g) * scale, u(g) * scale, 0};
            const Vec3 d = normalize(Vec3{u(g) * 0.1, u(g) * 0.1, 1});
            const Roots r = intersect(s, o, d);
            if (r.count == 0) continue;
            const Vec3 p = o + d * r.t[0];
            const double e = point_error_bound(s, p);
            const Vec3 n = s.normal(p);
            EXPECT_GT(s.signed_distance(p + n * (2 * e)), 0.0);
            EXPECT_LT(s.signed_distance(p - n * (2 * e)), 0.0);
            EXPECT_LT(e, 1e-12 * scale * 100);
        }
    }
}

// The camera's azimuth (trace/SinCos.h): cos(2 pi u) and sin(2 pi u) against long double, within
// the bound derived there, for random u in [0, 1) (the camera's draws, 53-bit multiples of 2^-53),
// at the quarter and eighth turns and their neighbouring doubles (the reduction's rounding ties and
// its largest remainders), and for tiny u; and exact at the quarter turns.
TEST(SinCos, TurnsWithinTheirBoundOfLongDouble) {
    const long double two_pi = 6.283185307179586476925286766559005768L;
    double worst = 0;
    auto check = [&](double u) {
        const CosSin got = cos_sin_turns(u);
        const long double a = two_pi * static_cast<long double>(u);
        const double ec = static_cast<double>(std::fabs(static_cast<long double>(got.cos) - std::cos(a)));
        const double es = static_cast<double>(std::fabs(static_cast<long double>(got.sin) - std::sin(a)));
        worst = std::max({worst, ec, es});
        ASSERT_LE(ec, tol::kTurnCosSin) << "u = " << u;
        ASSERT_LE(es, tol::kTurnCosSin) << "u = " << u;
    };
    std::mt19937_64 g(20261204);
    for (int i = 0; i < 2000000; ++i) check(static_cast<double>(g() >> 11) * 0x1.0p-53);
    for (int k = 0; k <= 16; ++k) {
        const double u = k / 16.0;
        check(u);
        check(std::nextafter(u, 0.0));
        check(std::nextafter(u, 1.0));
    }
    for (double u = 1e-300; u < 1; u *= 3.7) check(u);
    EXPECT_GT(worst, 0.0);  // the comparison saw rounding, so it could see more
    for (int k = 0; k < 4; ++k) {
        const CosSin q = cos_sin_turns(k / 4.0);
        EXPECT_EQ(q.cos, (k == 0) - (k == 2)) << k;
        EXPECT_EQ(q.sin, (k == 1) - (k == 3)) << k;
    }
    EXPECT_TRUE(std::isnan(cos_sin_turns(NAN).cos) && std::isnan(cos_sin_turns(INFINITY).sin));
}
