// Analytic surfaces: exact distances at points whose distance is known by construction, and the
// ellipsoid closest/farthest points checked by their defining optimality conditions.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/Surface.h"
#include "tests/Tolerances.h"

using namespace ltm;

TEST(Surface, PlaneSphereCylinderDistances) {
    const Surface p = Surface::plane({0, 0, 1}, {0, 0, 2});  // normal normalised to +z
    EXPECT_DOUBLE_EQ(p.signed_distance({5, -3, 4}), 3.0);
    EXPECT_DOUBLE_EQ(p.signed_distance({0, 0, -1}), -2.0);
    const Surface s = Surface::sphere({1, 2, 3}, 2.0);
    EXPECT_DOUBLE_EQ(s.signed_distance({1, 2, 8}), 3.0);   // 5 from the centre
    EXPECT_DOUBLE_EQ(s.signed_distance({1, 2, 3}), -2.0);  // the centre
    const Surface c = Surface::cylinder({0, 0, 0}, {0, 0, 1}, 3.0);
    EXPECT_DOUBLE_EQ(c.signed_distance({4, 0, 100}), 1.0);
    EXPECT_DOUBLE_EQ(c.signed_distance({0, 0, 7}), -3.0);
    // Projections land on the surface and the normal is the unit gradient.
    const Vec3 q = s.project({4, 6, 3});  // direction (3, 4, 0) / 5
    EXPECT_NEAR(q.x, 1 + 2 * 0.6, tol::kSurfaceExampleAbs);
    EXPECT_NEAR(q.y, 2 + 2 * 0.8, tol::kSurfaceExampleAbs);
    EXPECT_NEAR(length(c.normal({0, 5, 1}) - Vec3{0, 1, 0}), 0.0, tol::kSurfaceExampleAbs);
}

TEST(Surface, TorusAndCone) {
    // Torus of radii 3 and 1 about +z: (5, 0, 0) is 2 from the tube centre (3, 0, 0), i.e. 1 outside.
    const Surface t = Surface::torus({0, 0, 0}, {0, 0, 1}, 3.0, 1.0);
    EXPECT_DOUBLE_EQ(t.signed_distance({5, 0, 0}), 1.0);
    EXPECT_DOUBLE_EQ(t.signed_distance({0, 3, 0}), -1.0);
    EXPECT_DOUBLE_EQ(t.signed_distance({0, 0, 4}), 4.0);  // hypot(3, 4) - 1
    // Cone, apex at the origin, half-angle 45 deg: the point (2, 0, 0) is sqrt(2) from the
    // generator line q = h, and on its outside (away from the axis).
    const Surface k = Surface::cone({0, 0, 0}, {0, 0, 1}, kPi / 4);
    EXPECT_NEAR(k.signed_distance({2, 0, 0}), std::sqrt(2.0), tol::kSurfaceExampleAbs);
    EXPECT_NEAR(k.signed_distance({0, 0, 2}), -std::sqrt(2.0), tol::kSurfaceExampleAbs);
    EXPECT_NEAR(k.signed_distance({0, 3, -3}), 0.0, tol::kSurfaceExampleAbs);  // the lower nappe
    EXPECT_NEAR(k.signed_distance(k.project({1, 2, 5})), 0.0, tol::kConeProjectionAbs);
}

TEST(Surface, EulerRotationIsOrthonormal) {
    const Mat3 r = rotation_from_euler_deg({30, -70, 145});
    const Mat3 i = r * r.transposed();
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) EXPECT_NEAR(i(a, b), a == b ? 1.0 : 0.0, 4 * tol::kEps);
    // 90 degrees about z sends +x to +y.
    const Vec3 y = rotation_from_euler_deg({0, 0, 90}) * Vec3{1, 0, 0};
    EXPECT_NEAR(y.y, 1.0, tol::kSurfaceExampleAbs);
}

// The closest point x of an ellipsoid to y satisfies: x on the ellipsoid, and y - x parallel to the
// gradient at x (Lagrange). The farthest point satisfies the same with y - x antiparallel; both are
// compared with a dense sample of the surface, which no sample may beat.
TEST(Surface, EllipsoidExtremePointsSatisfyLagrangeConditions) {
    const Vec3 e{3.0, 1.5, 0.4};
    std::mt19937_64 g(7);
    std::uniform_real_distribution<double> u(-6, 6);
    std::vector<Vec3> samples;
    for (int i = 0; i <= 400; ++i)
        for (int j = 0; j < 400; ++j) {
            const double th = kPi * i / 400, ph = 2 * kPi * j / 400;
            samples.push_back({e.x * std::sin(th) * std::cos(ph), e.y * std::sin(th) * std::sin(ph), e.z * std::cos(th)});
        }
    for (int trial = 0; trial < 40; ++trial) {
        Vec3 y{u(g), u(g), u(g)};
        if (trial == 0) y = {0, 0, 5};   // on an axis: the degenerate case the guard handles
        if (trial == 1) y = {0.1, 0, 0};  // inside
        for (bool farthest : {false, true}) {
            const Vec3 x = farthest ? ellipsoid_farthest_point(e, y) : ellipsoid_closest_point(e, y);
            const double f = (x.x / e.x) * (x.x / e.x) + (x.y / e.y) * (x.y / e.y) + (x.z / e.z) * (x.z / e.z);
            EXPECT_NEAR(f, 1.0, tol::kEllipsoidExtremeOnSurface);
            const Vec3 grad = normalize(Vec3{x.x / (e.x * e.x), x.y / (e.y * e.y), x.z / (e.z * e.z)});
            const Vec3 d = y - x;
            EXPECT_LE(length(cross(grad, d)), 1e-9 * std::max(1.0, length(d)));
            const double dist = length(d);
            for (const auto& s : samples) {
                if (farthest) ASSERT_GE(dist, distance(y, s) - 1e-12);
                else ASSERT_LE(dist, distance(y, s) + 1e-12);
            }
        }
    }
}

TEST(Surface, EllipsoidSignedDistanceMatchesSphere) {
    // An ellipsoid with equal semi-axes is a sphere: distance |p - c| - r.
    const Surface e = Surface::ellipsoid({1, 1, 1}, rotation_from_euler_deg({10, 20, 30}), {2, 2, 2});
    EXPECT_NEAR(e.signed_distance({1, 1, 5}), 2.0, tol::rotated_ellipsoid_distance());
    EXPECT_NEAR(e.signed_distance({1.5, 1, 1}), -1.5, tol::rotated_ellipsoid_distance());
}
