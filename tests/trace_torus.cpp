// Torus (U-groove) intersections: the quartic's roots against closed forms, including chords far
// shorter than the tube (trace/Intersect.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "trace/Intersect.h"

using namespace ltm;

namespace {

// A tolerance for a root t of the torus quartic: its rounding is ~eps A^2 / |f'(t)|, with
// A ~ (R + r)^2 and |f'| >= 8 R^2 r |cos| at a crossing at angle `cos` to the tube; 1e3 eps (R + r)
// covers the geometric factors of these tests (R <= 50, r >= 0.01).
double root_tolerance(double R, double r) { return 1e3 * std::numeric_limits<double>::epsilon() * (R + r) * (R + r) / r; }

}  // namespace

TEST(Torus, EquatorialRayMeetsTheTubeAtFourExactPoints) {
    for (double R : {5.0, 50.0})
        for (double r : {0.01, 0.125, 1.0}) {
            const Surface s = Surface::torus({0.3, -0.2, 1.1}, {0, 0, 1}, R, r);
            const Vec3 o{0.3 - 2 * R, -0.2, 1.1};
            const Roots h = intersect(s, o, {1, 0, 0});
            ASSERT_EQ(h.count, 4) << R << " " << r;
            // From x = -2 R relative to the centre, the tube is crossed where |x| = R +- r.
            const double want[4] = {2 * R - (R + r), 2 * R - (R - r), 2 * R + (R - r), 2 * R + (R + r)};
            for (int i = 0; i < 4; ++i) EXPECT_NEAR(h.t[i], want[i], root_tolerance(R, r)) << i;
        }
}

TEST(Torus, ChordsFarShorterThanTheTubeAreFound) {
    // A ray along y at x = R, height z = r - delta above the tube's centre circle: it crosses the
    // tube where rho = sqrt(R^2 + y^2) <= R + w, w = sqrt(r^2 - z^2), so at y = +-sqrt((R + w)^2 - R^2)
    // (a chord of about 2 sqrt(2 R w)). delta down to 1e-9 r: chords down to ~1e-3 of the tube.
    const double R = 5.0, r = 0.125;
    const Surface s = Surface::torus({0, 0, 0}, {0, 0, 1}, R, r);
    for (double delta : {1e-2, 1e-4, 1e-6, 1e-8, 1e-9}) {
        const double z = r - delta * r;
        const double w = std::sqrt((r - z) * (r + z));
        const double y = std::sqrt(w * (2 * R + w));
        const Roots h = intersect(s, {R, -10, z}, {0, 1, 0});
        ASSERT_EQ(h.count, 2) << "delta " << delta;
        // Near grazing the roots are ill-conditioned: |f'| shrinks with the chord, so the bound
        // grows as 1 / sqrt(delta).
        const double tol = root_tolerance(R, r) / std::sqrt(delta);
        EXPECT_NEAR(h.t[0], 10 - y, tol) << "delta " << delta;
        EXPECT_NEAR(h.t[1], 10 + y, tol) << "delta " << delta;
    }
    // Clear of the tube by 1e-9 r: nothing.
    EXPECT_EQ(intersect(s, {R, -10, r * (1 + 1e-9)}, {0, 1, 0}).count, 0);
}

TEST(Torus, RandomRaysAgreeWithTheDistanceSignAlongThem) {
    // Every root is a sign change of the exact distance to the tube (checked just before and after
    // it), and between consecutive roots the distance keeps one sign (checked at the midpoints).
    const double R = 50.0, r = 0.03;
    const Surface s = Surface::torus({0, 0, 47.0}, {0, 0, 1}, R, r);
    std::mt19937_64 g(11);
    std::uniform_real_distribution<double> u(-1, 1);
    int hits = 0;
    for (int n = 0; n < 20000; ++n) {
        // Rays aimed at random points of the tube's neighbourhood from random directions.
        const double phi = 3.14159 * u(g);
        const Vec3 target{(R + 1.5 * r * u(g)) * std::cos(phi), (R + 1.5 * r * u(g)) * std::sin(phi), 47.0 + 1.5 * r * u(g)};
        Vec3 d{u(g), u(g), u(g)};
        d = normalize(d);
        const Vec3 o = target - d * 3.0;
        const Roots h = intersect(s, o, d);
        for (int i = 0; i < h.count; ++i) {
            const double t = h.t[i], e = 1e-7;
            const double before = s.signed_distance(o + d * (t - e)), after = s.signed_distance(o + d * (t + e));
            EXPECT_LT(before * after, 0) << "ray " << n << " root " << i;
            if (i + 1 < h.count) {
                const double mid = s.signed_distance(o + d * (0.5 * (t + h.t[i + 1])));
                EXPECT_GT(std::fabs(mid), 0);
            }
        }
        hits += h.count;
    }
    EXPECT_GT(hits, 10000);
}
