// The geometric draws of sampled datasets (defects/Sampling.h): uniform over the glass, over a
// face's area, over rotations; bubble populations' radii. Each is checked against the closed form of its distribution with
// z-tests on seeded draws (|z| below the Bonferroni bound for the tests in this file).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "defects/Sampling.h"
#include "geometry/Lens.h"
#include "tests/Tolerances.h"

using namespace ltm;

namespace {

constexpr int kChecks = 17;  // z-tests in this file, for the Bonferroni bound
const double kZ = tol::normal_two_sided_quantile(tol::kFamilyAlpha / kChecks);

struct Source {
    std::mt19937_64 g;
    explicit Source(std::uint64_t seed) : g(seed) {}
    Uniform01 u() {
        return [this] { return static_cast<double>(g() >> 11) * 0x1.0p-53; };
    }
};

// A window (flat faces) of the given thickness and diameter, mm.
Lens window(double thickness, double diameter) {
    LensSpec s;
    s.r1 = s.r2 = INFINITY;
    s.center_thickness = thickness;
    s.diameter = diameter;
    return Lens(s);
}

// The z-score of a sample mean against its expectation mu, for draws of variance var.
double z_of(double mean, double mu, double var, long n) { return (mean - mu) / std::sqrt(var / static_cast<double>(n)); }

}  // namespace

TEST(Bubbles, RadiiAreUniformWhateverRoomTheyFind) {
    // A window 1 mm thick: a bubble of radius r fits in 1 - 2r of the thickness, so a radius redrawn
    // with its rejected positions would have density proportional to 1 - 2r on [0.1, 0.45] (mean
    // 0.230 instead of 0.275: 7.8 sigma at n = 300). Drawn once, radii are uniform: mean
    // (min + max) / 2, variance (max - min)^2 / 12.
    const Lens lens = window(1, 40);
    BubblePopulation p;
    p.count = 300;
    p.min_radius = 0.1;
    p.max_radius = 0.45;
    p.seed = 5;
    const auto bubbles = sample_bubbles(lens, p);
    ASSERT_EQ(bubbles.size(), 300u);
    double mean = 0;
    for (const auto& b : bubbles) mean += b.semi_axes.x / p.count;
    EXPECT_LT(std::fabs(z_of(mean, 0.275, 0.35 * 0.35 / 12, p.count)), kZ);
}

TEST(GlassPoints, UniformOverAWindowsVolume) {
    // A window of radius a and thickness t: rho^2 / a^2 and (z + t/2) / t are independent and
    // uniform on [0, 1] (mean 1/2, variance 1/12).
    const Lens lens = window(3, 20);
    Source src(1);
    const long n = 20000;
    double m1 = 0, m2 = 0;
    for (long i = 0; i < n; ++i) {
        const Vec3 p = uniform_point_in_glass(lens, src.u());
        ASSERT_GT(lens.signed_distance(p), 0);
        m1 += (p.x * p.x + p.y * p.y) / 100.0;
        m2 += (p.z + 1.5) / 3.0;
    }
    EXPECT_LT(std::fabs(z_of(m1 / n, 0.5, 1.0 / 12, n)), kZ);
    EXPECT_LT(std::fabs(z_of(m2 / n, 0.5, 1.0 / 12, n)), kZ);
}

TEST(FacePoints, UniformOverTheAreaOfASphericalCap) {
    // On a cap of sphere radius |R| over rho <= a (height h), the area above height w is
    // 2 pi |R| w (Archimedes), so the height of a uniform point is uniform on [0, h]; the naive
    // draw uniform in the projected disc would give rho^2 uniform instead, with height mean
    // below h / 2 (0.45 of h for r1 = 15, a = 12.5: 17 sigma at these n). Both faces of a strongly
    // curved biconvex lens and of a concave one; points lie on the face and the inward normal
    // points into the glass.
    for (double r1 : {15.0, -20.0}) {
        LensSpec s;
        s.r1 = r1;
        s.r2 = -40;
        s.center_thickness = 12;
        s.diameter = 25;
        const Lens lens(s);
        for (int side : {0, 1}) {
            const double R = side == 0 ? s.r1 : s.r2;
            const double h = std::fabs(sphere_sag(R, 12.5));
            Source src(7 + side);
            const long n = 100000;
            double mean_w = 0;
            for (long i = 0; i < n; ++i) {
                const FacePoint f = uniform_point_on_face(lens, side, src.u());
                const double rho = std::hypot(f.point.x, f.point.y);
                ASSERT_LE(rho, 12.5 + 1e-12);
                const double zf = side == 0 ? lens.z_front(rho) : lens.z_back(rho);
                ASSERT_NEAR(f.point.z, zf, tol::face_point_height(12.5, 12.5 / std::sqrt(15.0 * 15.0 - 12.5 * 12.5), 13.0));
                // (Within 1e-3 of the rim a concave face's inward normal leaves through the rim.)
                if (rho < 12.5 - 1e-3) {
                    EXPECT_GT(lens.signed_distance(f.point + f.inward * 1e-4), 0) << "side " << side << " rho " << rho;
                }
                mean_w += std::fabs(sphere_sag(R, rho)) / h;
            }
            EXPECT_LT(std::fabs(z_of(mean_w / n, 0.5, 1.0 / 12, n)), kZ) << "r1 " << r1 << " side " << side;
        }
    }
}

TEST(FacePoints, UniformOverAFlatFaceAndABallsHemisphere) {
    LensSpec w;
    w.r1 = w.r2 = INFINITY;
    w.center_thickness = 2;
    w.diameter = 10;
    Source src(3);
    const long n = 20000;
    double m = 0;
    for (long i = 0; i < n; ++i) {
        const FacePoint f = uniform_point_on_face(Lens(w), 1, src.u());
        m += (f.point.x * f.point.x + f.point.y * f.point.y) / 25.0;  // rho^2 / a^2 uniform
        ASSERT_EQ(f.point.z, 1.0);
        ASSERT_EQ(f.inward.z, -1.0);
    }
    EXPECT_LT(std::fabs(z_of(m / n, 0.5, 1.0 / 12, n)), kZ);
    // A ball's front hemisphere: the height w = z + R is uniform on [0, R].
    const Lens ball(ball_spec(4.0, 1.5));
    double mw = 0;
    for (long i = 0; i < n; ++i) mw += (uniform_point_on_face(ball, 0, src.u()).point.z + 4.0) / 4.0;
    EXPECT_LT(std::fabs(z_of(mw / n, 0.5, 1.0 / 12, n)), kZ);
}

TEST(Rotations, UniformOverSO3AndTheEulerAnglesGiveThemBack) {
    // Haar measure: E[R] = 0, and each entry has variance 1/3 (a column is a uniform unit vector).
    Source src(5);
    const long n = 20000;
    std::array<double, 9> mean{};
    for (long i = 0; i < n; ++i) {
        const Mat3 R = rotation_from_euler_deg(uniform_rotation_euler_deg(src.u()));
        for (int k = 0; k < 9; ++k) mean[static_cast<size_t>(k)] += R.m[static_cast<size_t>(k)] / n;
    }
    for (int k = 0; k < 9; k += 4) EXPECT_LT(std::fabs(z_of(mean[static_cast<size_t>(k)], 0.0, 1.0 / 3, n)), kZ) << k;
    // euler_deg_from_rotation inverts rotation_from_euler_deg (to rounding), gimbal lock included.
    std::mt19937_64 g(9);
    std::uniform_real_distribution<double> a(-179, 179), b(-89, 89);
    for (int i = 0; i < 1000; ++i) {
        const Vec3 e{a(g), b(g), a(g)};
        const Vec3 back = euler_deg_from_rotation(rotation_from_euler_deg(e));
        const double te = tol::euler_roundtrip_deg(std::cos(e.y * kPi / 180));
        EXPECT_NEAR(back.x, e.x, te);
        EXPECT_NEAR(back.y, e.y, te);
        EXPECT_NEAR(back.z, e.z, te);
    }
    for (double by : {90.0, -90.0}) {
        const Mat3 R = rotation_from_euler_deg({30, by, 10});
        const Mat3 S = rotation_from_euler_deg(euler_deg_from_rotation(R));
        for (int k = 0; k < 9; ++k) EXPECT_NEAR(S.m[static_cast<size_t>(k)], R.m[static_cast<size_t>(k)], tol::gimbal_roundtrip_entry());
    }
}
