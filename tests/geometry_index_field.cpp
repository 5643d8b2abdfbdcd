// Index fields against hand formulas, the exact range of a quadratic over the lens solid against
// closed forms for every kind of lens and against dense samples of random quadratics, and the
// validity checks of a field (index_field_problems).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "geometry/IndexField.h"
#include "geometry/Lens.h"
#include "tests/Tolerances.h"

using namespace ltm;

namespace {

struct Kind {
    const char* name;
    LensSpec spec;
};

// Every sign combination of radii (as in geometry_lens.cpp), a hemispherical face (|r1| = a: its
// cap meets the rim tangentially) and a ball.
std::vector<Kind> lens_kinds() {
    return {
        {"double-convex", {50, -50, 6, 25, 1.5168}},
        {"plano-convex", {40, INFINITY, 5, 25, 1.5168}},
        {"convex-plano", {INFINITY, -40, 5, 25, 1.5168}},
        {"positive-meniscus", {30, 60, 5, 25, 1.5168}},
        {"negative-meniscus", {60, 30, 4, 25, 1.5168}},
        {"plano-concave", {INFINITY, 40, 2, 25, 1.5168}},
        {"biconcave", {-40, 40, 2, 25, 1.5168}},
        {"window", {INFINITY, INFINITY, 3, 25, 1.5168}},
        {"hemisphere", {12.5, INFINITY, 14, 25, 1.5168}},
        {"ball", ball_spec(10, 1.5168)},
    };
}

LensSpec scaled(LensSpec s, double k) {
    if (s.ball) return ball_spec(s.r1 * k, s.ior);
    s.r1 *= k, s.r2 *= k, s.center_thickness *= k, s.diameter *= k;
    return s;
}

QuadraticForm form(double c, Vec3 b, Mat3 H) {
    QuadraticForm q;
    q.c = c, q.b = b, q.H = H;
    return q;
}
Mat3 diag(double x, double y, double z) { return Mat3{{x, 0, 0, 0, y, 0, 0, 0, z}}; }

double frobenius(const Mat3& H) {
    double s = 0;
    for (double v : H.m) s += v * v;
    return std::sqrt(s);
}

// L of tol::quadratic_extreme: bounds the solid's points and the centres and radii of its spheres.
double scale_of(const Lens& lens) {
    const LensSpec& s = lens.spec();
    const double a = lens.aperture_radius();
    double L = std::hypot(a, std::fmax(std::fmax(std::fabs(lens.z_front(0)), std::fabs(lens.z_front(a))),
                                       std::fmax(std::fabs(lens.z_back(0)), std::fabs(lens.z_back(a)))));
    if (!std::isinf(s.r1)) L = std::fmax(L, std::fabs(-0.5 * s.center_thickness + s.r1) + std::fabs(s.r1));
    if (!std::isinf(s.r2)) L = std::fmax(L, std::fabs(0.5 * s.center_thickness + s.r2) + std::fabs(s.r2));
    return L;
}

// Q of tol::quadratic_extreme.
double magnitude(const QuadraticForm& q, double L) {
    return std::fabs(q.c) + length(q.b) * L + frobenius(q.H) * L * L;
}

double extreme_tol(const Lens& lens, const QuadraticForm& q) {
    return tol::quadratic_extreme(magnitude(q, scale_of(lens)));
}

}  // namespace

TEST(IndexField, TypeNames) {
    EXPECT_STREQ(to_string(IndexFieldType::Uniform), "uniform");
    EXPECT_STREQ(to_string(IndexFieldType::LinearN2), "linear_n2");
    EXPECT_STREQ(to_string(IndexFieldType::RadialN2), "radial_n2");
    EXPECT_STREQ(to_string(IndexFieldType::SphericalN2), "spherical_n2");
    EXPECT_STREQ(to_string(IndexFieldType::QuadraticN2), "quadratic_n2");
    EXPECT_STREQ(to_string(IndexFieldType::LinearN), "linear_n");
}

TEST(IndexField, EachKindMatchesItsHandFormula) {
    // Every expected value below is a short exact decimal computation; the tolerance is
    // tol::quadratic_agreement of the terms' magnitude Q (a few units).
    auto expect_vec = [](const Vec3& got, const Vec3& want, double t) {
        EXPECT_NEAR(got.x, want.x, t);
        EXPECT_NEAR(got.y, want.y, t);
        EXPECT_NEAR(got.z, want.z, t);
    };
    IndexField f;
    f.ior = 1.5;
    {
        // uniform: n^2 = 2.25 everywhere, grad 0; n2_form is c = ior^2, b = 0, H = 0.
        const Vec3 x{3, -4, 5};
        EXPECT_NEAR(f.n2(x), 2.25, tol::quadratic_agreement(2.25));
        EXPECT_NEAR(f.n(x), 1.5, tol::quadratic_agreement(2.25));
        EXPECT_EQ(f.grad_n2(x), Vec3(0, 0, 0));
        EXPECT_EQ(f.n2_form().H, Mat3::zero());
        EXPECT_FALSE(f.graded());
    }
    {
        // linear_n2: n^2 = 2.25 + (0.01, -0.02, 0.03) . (1, 2, 3) = 2.25 + 0.01 - 0.04 + 0.09 = 2.31.
        f.type = IndexFieldType::LinearN2;
        f.gradient = {0.01, -0.02, 0.03};
        const Vec3 x{1, 2, 3};
        const double t = tol::quadratic_agreement(2.25 + 0.14);
        EXPECT_NEAR(f.n2(x), 2.31, t);
        expect_vec(f.grad_n2(x), f.gradient, t);
        EXPECT_NEAR(f.n(x), std::sqrt(2.31), t);
    }
    {
        // radial_n2: n^2 = ior^2 (1 - G^2 (x^2 + y^2)) = 2.56 (1 - 0.0025 * 25) = 2.4 at (3, 4, 7);
        // grad = -2 ior^2 G^2 (x, y, 0) = -0.0128 (3, 4, 0) = (-0.0384, -0.0512, 0).
        f.type = IndexFieldType::RadialN2;
        f.ior = 1.6;
        f.g = 0.05;
        const Vec3 x{3, 4, 7};
        const double t = tol::quadratic_agreement(2.56 + 2.56 * 0.0025 * 74);
        EXPECT_NEAR(f.n2(x), 2.4, t);
        expect_vec(f.grad_n2(x), {-0.0384, -0.0512, 0}, t);
        const QuadraticForm q = f.n2_form();
        EXPECT_EQ(q.H(2, 2), 0.0);
        EXPECT_EQ(q.H(0, 0), q.H(1, 1));
    }
    {
        // spherical_n2 (Luneburg, R = 10): n^2 = 2 (1 - |x|^2 / 200) = 1 at |(0, 6, 8)| = 10;
        // grad = -2 ior^2 g^2 x = -0.02 x = (0, -0.12, -0.16).
        f.type = IndexFieldType::SphericalN2;
        f.ior = std::sqrt(2.0);
        f.g = 1.0 / (10 * std::sqrt(2.0));
        const Vec3 x{0, 6, 8};
        const double t = tol::quadratic_agreement(2.0 + 2.0 * 0.005 * 100);
        EXPECT_NEAR(f.n2(x), 1.0, t);
        EXPECT_NEAR(f.n(x), 1.0, t);
        expect_vec(f.grad_n2(x), {0, -0.12, -0.16}, t);
        // Beyond |x| = R sqrt 2 n^2 < 0: n is reported as 0 (no real index).
        EXPECT_LT(f.n2({0, 0, 20}), 0.0);
        EXPECT_EQ(f.n({0, 0, 20}), 0.0);
    }
    {
        // quadratic_n2 at x = (1, -2, 3): b . x = 0.1 - 0.6 = -0.5; H x = (0.02 - 0.02, 0.01 + 0.08
        // + 0.015, -0.01 + 0.03) = (0, 0.105, 0.02); x^T H x / 2 = (-0.21 + 0.06) / 2 = -0.075:
        // n^2 = 2.25 - 0.5 - 0.075 = 1.675, grad = b + H x = (0.1, 0.105, -0.18).
        f.type = IndexFieldType::QuadraticN2;
        f.ior = 1.5;
        f.gradient = {0.1, 0, -0.2};
        f.hessian = Mat3{{0.02, 0.01, 0, 0.01, -0.04, 0.005, 0, 0.005, 0.01}};
        const Vec3 x{1, -2, 3};
        const double t = tol::quadratic_agreement(2.25 + 0.7 + 0.5);
        EXPECT_NEAR(f.n2(x), 1.675, t);
        expect_vec(f.grad_n2(x), {0.1, 0.105, -0.18}, t);
    }
    {
        // linear_n: n = 1.5 + 0.01 * 10 = 1.6 at (5, 5, 10); n^2 = 2.56; grad n^2 = 2 n gradient
        // = (0, 0, 0.032). It has no closed-form quadratic n^2.
        f.type = IndexFieldType::LinearN;
        f.gradient = {0, 0, 0.01};
        const Vec3 x{5, 5, 10};
        const double t = tol::quadratic_agreement(2.56);
        EXPECT_NEAR(f.n(x), 1.6, t);
        EXPECT_NEAR(f.n2(x), 2.56, t);
        expect_vec(f.grad_n2(x), {0, 0, 0.032}, t);
        EXPECT_FALSE(f.closed_form());
        EXPECT_THROW(f.n2_form(), std::logic_error);
    }
}

TEST(QuadraticRange, ConstantIsItsOwnRange) {
    // q = 0.7: every stratum's form vanishes (A = 0, beta = 0: the hard case of the whole sphere or
    // circle), and each candidate's value is c itself.
    const QuadraticForm q = form(0.7, {}, Mat3::zero());
    for (const auto& kind : lens_kinds()) {
        const QuadraticRange r = quadratic_range(Lens(kind.spec), q);
        EXPECT_EQ(r.min, 0.7) << kind.name;
        EXPECT_EQ(r.max, 0.7) << kind.name;
    }
}

TEST(QuadraticRange, SquaredRadiusOverABall) {
    // |x|^2 over the ball of radius 10: min 0 at the centre (the interior stationary point of a
    // positive definite form), max R^2 = 100 on the whole sphere (the hard case with A = R^2 I and
    // beta = 0 on each hemisphere: any point; the vertex is picked).
    const Lens lens(ball_spec(10, 1.5));
    const QuadraticForm q = form(0, {}, Mat3::identity() * 2.0);
    const QuadraticRange r = quadratic_range(lens, q);
    const double t = extreme_tol(lens, q);
    EXPECT_NEAR(r.min, 0.0, t);
    EXPECT_NEAR(r.max, 100.0, t);
    EXPECT_NEAR(length(r.argmin), 0.0, tol::on_surface(10));
    EXPECT_NEAR(length(r.argmax), 10.0, tol::on_surface(10));
}

TEST(QuadraticRange, LinearOverAWindowReachesTheRim) {
    // x over the window of semi-diameter a = 12.5: -a .. a, on the rim's generators x = -+a (whole
    // segments of stationary points: the edge circles find their ends).
    const Lens lens({INFINITY, INFINITY, 3, 25, 1.5});
    const QuadraticForm q = form(0, {1, 0, 0}, Mat3::zero());
    const QuadraticRange r = quadratic_range(lens, q);
    const double t = extreme_tol(lens, q);
    EXPECT_NEAR(r.min, -12.5, t);
    EXPECT_NEAR(r.max, 12.5, t);
    EXPECT_NEAR(r.argmin.x, -12.5, t);
    EXPECT_NEAR(r.argmax.x, 12.5, t);
}

TEST(QuadraticRange, AxialLinearOverADoubleConvexLensIsAtTheVertices) {
    // z over the double-convex lens (t = 6): both faces bulge outward, so z is extreme at the
    // vertices (0, 0, -+3).
    const Lens lens({50, -50, 6, 25, 1.5});
    const QuadraticForm q = form(0, {0, 0, 1}, Mat3::zero());
    const QuadraticRange r = quadratic_range(lens, q);
    const double t = extreme_tol(lens, q);
    const double p = tol::on_surface(scale_of(lens));
    EXPECT_NEAR(r.min, -3.0, t);
    EXPECT_NEAR(r.max, 3.0, t);
    EXPECT_NEAR(distance(r.argmin, {0, 0, -3}), 0.0, p);
    EXPECT_NEAR(distance(r.argmax, {0, 0, 3}), 0.0, p);
}

TEST(QuadraticRange, SaddleOverAWindow) {
    // x^2 - y^2 over the window: min -a^2 on the generators x = 0, y = -+a and max a^2 on y = 0,
    // x = -+a (a = 12.5): x^2 <= rho^2 - y^2 <= a^2 - y^2.
    const Lens lens({INFINITY, INFINITY, 3, 25, 1.5});
    const QuadraticForm q = form(0, {}, diag(2, -2, 0));
    const QuadraticRange r = quadratic_range(lens, q);
    const double t = extreme_tol(lens, q);
    const double p = tol::on_surface(scale_of(lens));
    EXPECT_NEAR(r.min, -156.25, t);
    EXPECT_NEAR(r.max, 156.25, t);
    EXPECT_NEAR(std::fabs(r.argmin.y), 12.5, p);
    EXPECT_NEAR(std::fabs(r.argmax.x), 12.5, p);
}

TEST(QuadraticRange, SaddleWithItsMinimumOnAnEdgeCircle) {
    // q = x^2 - y^2 + z over the double-convex lens (r = +-50, t = 6, a = 12.5). Over the solid
    // q >= -rho^2 + z_front(rho), and d/drho (-rho^2 + z_front(rho)) = -2 rho + rho / sqrt(R^2 - rho^2)
    // < 0, so the minimum is at rho = a, y = -+a, z = z_front(a): -a^2 + z_front(a), isolated
    // points of the front edge circle. Likewise q <= rho^2 + z_back(rho), increasing: the maximum
    // a^2 + z_back(a) at x = -+a on the back edge circle.
    const Lens lens({50, -50, 6, 25, 1.5});
    const double a = 12.5;
    const QuadraticForm q = form(0, {0, 0, 1}, diag(2, -2, 0));
    const QuadraticRange r = quadratic_range(lens, q);
    const double t = extreme_tol(lens, q);
    const double p = tol::on_surface(scale_of(lens));
    EXPECT_NEAR(r.min, -a * a + lens.z_front(a), t);
    EXPECT_NEAR(r.max, a * a + lens.z_back(a), t);
    EXPECT_NEAR(std::fabs(r.argmin.y), a, p);
    EXPECT_NEAR(r.argmin.z, lens.z_front(a), p);
    EXPECT_NEAR(std::fabs(r.argmax.x), a, p);
    EXPECT_NEAR(r.argmax.z, lens.z_back(a), p);
}

TEST(QuadraticRange, DistanceFromAPointBeyondACapIsMinimalInsideTheCap) {
    // q = |x - p|^2 with p = C + (R + d) v beyond the front cap of the double-convex lens (centre
    // C = (0, 0, 47), R = 50), v = (sin 10 deg, 0, -cos 10 deg), d = 5. The solid lies in the ball
    // |x - C| <= R, so |x - p| >= d, with equality at the foot point C + R v, which is on the cap
    // (its rho = R sin 10 deg = 8.68 < a = 12.5): min = d^2 = 25.
    const Lens lens({50, -50, 6, 25, 1.5});
    const double th = 10 * kPi / 180;
    const Vec3 C{0, 0, 47}, v{std::sin(th), 0, -std::cos(th)};
    const Vec3 p = C + v * 55.0;
    const QuadraticForm q = form(length2(p), p * -2.0, Mat3::identity() * 2.0);
    const QuadraticRange r = quadratic_range(lens, q);
    EXPECT_NEAR(r.min, 25.0, extreme_tol(lens, q));
    EXPECT_NEAR(distance(r.argmin, C + v * 50.0), 0.0, tol::on_surface(scale_of(lens)));
}

TEST(QuadraticRange, HardCaseContinuaOnABall) {
    // q = -(x^2 + y^2) on the ball of radius 10 (beta = 0 on both hemispheres, A = diag(-R^2, -R^2,
    // 0)): the maximum 0 on the whole z axis (a line of interior stationary points, seen at the
    // poles, the hard case of the simple eigenvalue 0) and the minimum -R^2 = -100 on the whole
    // equator (the hard case of the double eigenvalue -R^2, and the equator circle, on which q is
    // constant).
    const Lens lens(ball_spec(10, 1.5));
    const QuadraticForm q = form(0, {}, diag(-2, -2, 0));
    const QuadraticRange r = quadratic_range(lens, q);
    const double t = extreme_tol(lens, q);
    const double p = tol::on_surface(10);
    EXPECT_NEAR(r.max, 0.0, t);
    EXPECT_NEAR(r.min, -100.0, t);
    EXPECT_NEAR(std::hypot(r.argmax.x, r.argmax.y), 0.0, p);
    EXPECT_NEAR(std::hypot(r.argmin.x, r.argmin.y), 10.0, p);
    EXPECT_NEAR(r.argmin.z, 0.0, p);
}

TEST(QuadraticRange, ConcaveLens) {
    // Biconcave (r1 = -40, r2 = 40, t = 2): the faces recede toward the rim, so z is extreme on
    // the edge circles, z_front(a) = -1 - sag(40, a) and z_back(a) = 1 + sag(40, a) (every point of
    // the circle). |x|^2: min 0 at the centre (interior), max a^2 + z_back(a)^2 on both edge
    // circles (for each rho, z^2 is largest at a face, and |z_face(rho)| grows with rho).
    const Lens lens({-40, 40, 2, 25, 1.5});
    const double a = 12.5;
    {
        const QuadraticForm q = form(0, {0, 0, 1}, Mat3::zero());
        const QuadraticRange r = quadratic_range(lens, q);
        const double t = extreme_tol(lens, q);
        EXPECT_NEAR(r.min, -1 - sphere_sag(40, a), t);
        EXPECT_NEAR(r.max, 1 + sphere_sag(40, a), t);
        EXPECT_NEAR(std::hypot(r.argmin.x, r.argmin.y), a, tol::on_surface(scale_of(lens)));
    }
    {
        const QuadraticForm q = form(0, {}, Mat3::identity() * 2.0);
        const QuadraticRange r = quadratic_range(lens, q);
        const double t = extreme_tol(lens, q);
        const double ze = 1 + sphere_sag(40, a);
        EXPECT_NEAR(r.min, 0.0, t);
        EXPECT_NEAR(r.max, a * a + ze * ze, t);
    }
}

TEST(QuadraticRange, Meniscus) {
    // Positive meniscus (r1 = 30, r2 = 60, t = 5): both faces rise toward the rim, so z has its
    // minimum -2.5 at the front vertex and its maximum z_back(a) = 2.5 + sag(60, a) on the back
    // edge circle. |x|^2: min 0 at the centre, max a^2 + z_back(a)^2 there too (z_back(a) = 3.82
    // exceeds every |z| of the front face, whose z is in [-2.5, 0.23]).
    const Lens lens({30, 60, 5, 25, 1.5});
    const double a = 12.5, zb = 2.5 + sphere_sag(60, a);
    {
        const QuadraticForm q = form(0, {0, 0, 1}, Mat3::zero());
        const QuadraticRange r = quadratic_range(lens, q);
        const double t = extreme_tol(lens, q);
        EXPECT_NEAR(r.min, -2.5, t);
        EXPECT_NEAR(r.max, zb, t);
        EXPECT_NEAR(distance(r.argmin, {0, 0, -2.5}), 0.0, tol::on_surface(scale_of(lens)));
    }
    {
        const QuadraticForm q = form(0, {}, Mat3::identity() * 2.0);
        const QuadraticRange r = quadratic_range(lens, q);
        const double t = extreme_tol(lens, q);
        EXPECT_NEAR(r.min, 0.0, t);
        EXPECT_NEAR(r.max, a * a + zb * zb, t);
    }
}

// For random quadratics on every kind of lens and at three scales, the exact range contains q at
// dense samples of the solid and of each stratum, and its extremes are values of q at points of
// the solid. The forms include the degenerate structures the method treats separately: repeated
// eigenvalues in a rotated frame, rank one (semi-definite), an interior stationary point,
// axis-aligned forms with an exactly repeated eigenvalue and beta along the axis (exact hard
// cases), H_zz = 0 (the rim without the elimination of z), and strongly curved forms (|H| a^2 ~ 100
// |b| a: caps whose extremes are local ones of their sphere, the secular equation's inner roots).
TEST(QuadraticRange, RandomFormsBoundEverySample) {
    std::mt19937_64 rng(20240611);
    std::normal_distribution<double> normal(0, 1);
    std::uniform_real_distribution<double> uniform(0, 1);
    const struct {
        double scale;
        int forms;
    } scales[] = {{1.0, 200}, {1e-3, 50}, {1e3, 50}};
    for (const auto& kind : lens_kinds()) {
        for (const auto& sc : scales) {
            const Lens lens(scaled(kind.spec, sc.scale));
            SCOPED_TRACE(::testing::Message() << kind.name << " at scale " << sc.scale);
            const double a = lens.aperture_radius();
            const double z0 = lens.z_front(a), z1 = lens.z_back(a);
            const double zlo = std::fmin(lens.z_front(0), z0), zhi = std::fmax(lens.z_back(0), z1);
            // Samples: 10,000 points of the solid by rejection in its bounding cylinder, 2,000 on each
            // face, 2,000 on the rim band and 1,000 on each edge circle.
            std::vector<Vec3> pts;
            auto disc = [&] {
                for (;;) {
                    const double x = a * (2 * uniform(rng) - 1), y = a * (2 * uniform(rng) - 1);
                    if (std::hypot(x, y) <= a) return std::pair<double, double>(x, y);
                }
            };
            while (pts.size() < 10000) {
                const auto [x, y] = disc();
                const Vec3 p{x, y, zlo + (zhi - zlo) * uniform(rng)};
                if (lens.contains(p)) pts.push_back(p);
            }
            for (int side = 0; side < 2; ++side)
                for (int i = 0; i < 2000; ++i) {
                    const auto [x, y] = disc();
                    pts.push_back(lens.surface_point(side, x, y));
                }
            for (int i = 0; i < 2000; ++i) {
                const double phi = 2 * kPi * uniform(rng);
                pts.push_back({a * std::cos(phi), a * std::sin(phi), z0 + (z1 - z0) * uniform(rng)});
            }
            for (const double z : {z0, z1})
                for (int i = 0; i < 1000; ++i) {
                    const double phi = 2 * kPi * uniform(rng);
                    pts.push_back({a * std::cos(phi), a * std::sin(phi), z});
                }

            const double L = scale_of(lens);
            auto random_rotation = [&] {
                return rotation_from_euler_deg({360 * uniform(rng), 360 * uniform(rng), 360 * uniform(rng)});
            };
            for (int k = 0; k < sc.forms; ++k) {
                QuadraticForm q;
                q.c = normal(rng);
                q.b = Vec3(normal(rng), normal(rng), normal(rng)) / a;
                Mat3 H = Mat3::zero();
                const double h = 1.0 / (a * a);
                switch (k % 7) {
                    case 0:  // generic symmetric
                        for (int i = 0; i < 3; ++i)
                            for (int j = i; j < 3; ++j) H(i, j) = H(j, i) = h * normal(rng);
                        break;
                    case 1: {  // a repeated eigenvalue, rotated
                        const Mat3 R = random_rotation();
                        const double l = h * normal(rng);
                        H = R * diag(l, l, h * normal(rng)) * R.transposed();
                        break;
                    }
                    case 2: {  // rank one
                        const Vec3 v = random_rotation().column(0);
                        const double l = h * normal(rng);
                        for (int i = 0; i < 3; ++i)
                            for (int j = 0; j < 3; ++j) H(i, j) = l * v[i] * v[j];
                        break;
                    }
                    case 3: {  // definite or not, stationary at a random point of the bounding cylinder
                        for (int i = 0; i < 3; ++i)
                            for (int j = i; j < 3; ++j) H(i, j) = H(j, i) = h * normal(rng);
                        const auto [x, y] = disc();
                        q.b = -(H * Vec3(x, y, zlo + (zhi - zlo) * uniform(rng)));
                        break;
                    }
                    case 4: {  // axis-aligned, x-y symmetric, b along z
                        const double l = h * normal(rng);
                        H = diag(l, l, h * normal(rng));
                        q.b = {0, 0, q.b.z};
                        break;
                    }
                    case 5:  // H_zz = 0: q is linear along the rim's generators
                        for (int i = 0; i < 3; ++i)
                            for (int j = i; j < 3; ++j) H(i, j) = H(j, i) = h * normal(rng);
                        H(2, 2) = 0;
                        break;
                    case 6:  // generic and strongly curved: several local extremes on each cap
                        for (int i = 0; i < 3; ++i)
                            for (int j = i; j < 3; ++j) H(i, j) = H(j, i) = 100 * h * normal(rng);
                        break;
                }
                q.H = H;
                const QuadraticRange r = quadratic_range(lens, q);
                const double t = tol::quadratic_extreme(magnitude(q, L));
                ASSERT_EQ(r.min, q(r.argmin)) << "form " << k;
                ASSERT_EQ(r.max, q(r.argmax)) << "form " << k;
                // The extremes' points are in the solid up to the rounding of their coordinates
                // (<= 8 u L, as in tol::quadratic_extreme) and of signed_distance (a few u L).
                ASSERT_GE(lens.signed_distance(r.argmin), -tol::on_surface(L)) << "form " << k;
                ASSERT_GE(lens.signed_distance(r.argmax), -tol::on_surface(L)) << "form " << k;
                for (const Vec3& p : pts) {
                    const double v = q(p);
                    ASSERT_GE(v, r.min - t) << "form " << k << " at (" << p.x << ", " << p.y << ", " << p.z << ")";
                    ASSERT_LE(v, r.max + t) << "form " << k << " at (" << p.x << ", " << p.y << ", " << p.z << ")";
                }
            }
        }
    }
}

TEST(IndexRange, LuneburgLensReachesVacuumAtItsSurface) {
    // ior = sqrt 2, g = 1 / (R sqrt 2) typed to 15 significant digits, R = 10:
    // n^2 = 2 (1 - |x|^2 / (2 R^2)) is 1 on the sphere (to the rounding of g, ~1e-15) and 2 at the
    // centre; n >= 1 - kIndexBelowOneSlack, so the field is valid.
    const Lens lens(ball_spec(10, std::sqrt(2.0)));
    IndexField f;
    f.type = IndexFieldType::SphericalN2;
    f.ior = std::sqrt(2.0);
    f.g = 0.0707106781186548;
    const IndexRange r = index_range(lens, f);
    EXPECT_NEAR(r.n_min, 1.0, tol::luneburg_surface_index());
    EXPECT_NEAR(r.n_max, std::sqrt(2.0), tol::luneburg_surface_index());
    EXPECT_NEAR(length(r.argmin), 10.0, tol::on_surface(10));
    EXPECT_TRUE(index_field_problems(lens, f).empty());
}

TEST(IndexRange, GrinRodIsLowestOnTheRim) {
    // radial_n2 in a window (a = 12.5): n^2 = ior^2 (1 - G^2 rho^2), lowest on the rim:
    // 2.25 (1 - 0.0004 * 156.25) = 2.25 * 0.9375 = 2.109375.
    const Lens lens({INFINITY, INFINITY, 3, 25, 1.5});
    IndexField f;
    f.type = IndexFieldType::RadialN2;
    f.ior = 1.5;
    f.g = 0.02;
    const IndexRange r = index_range(lens, f);
    const double t = tol::quadratic_extreme(magnitude(f.n2_form(), scale_of(lens)));
    EXPECT_NEAR(r.n2_min, 2.109375, t);
    EXPECT_NEAR(r.n2_max, 2.25, t);
    EXPECT_NEAR(std::hypot(r.argmin.x, r.argmin.y), 12.5, tol::on_surface(scale_of(lens)));
}

TEST(IndexRange, LinearNChangingSignHasAZeroOfN) {
    // linear_n with n = 1.5 + 0.2 x over the window: n ranges over 1.5 -+ 2.5 = [-1, 4], so it
    // vanishes on the plane x = -7.5 inside the solid: n2_min = 0 there, n2_max = 16.
    const Lens lens({INFINITY, INFINITY, 3, 25, 1.5});
    IndexField f;
    f.type = IndexFieldType::LinearN;
    f.ior = 1.5;
    f.gradient = {0.2, 0, 0};
    const IndexRange r = index_range(lens, f);
    // n^2 = (1.5 + 0.2 x)^2 as a quadratic: c = 2.25, b = (0.6, 0, 0), H = diag(0.08, 0, 0).
    const double t = tol::quadratic_extreme(magnitude(form(2.25, {0.6, 0, 0}, diag(0.08, 0, 0)), scale_of(lens)));
    EXPECT_EQ(r.n2_min, 0.0);
    EXPECT_NEAR(r.n2_max, 16.0, t);
    EXPECT_NEAR(r.argmin.x, -7.5, tol::on_surface(scale_of(lens)));  // on the edge circles
    const auto p = index_field_problems(lens, f);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].key, "");
    EXPECT_NE(p[0].message.find("n^2 = 0 at "), std::string::npos) << p[0].message;
}

TEST(IndexFieldProblems, LuneburgWithTooSteepAGradientFallsBelowVacuum) {
    // g = 0.08, R = 10: n^2 = 2 (1 - 0.64) = 0.72 at the surface, n = 0.848528 < 1. The hint's bound
    // is sqrt(1 - 1/2) / 10 = 0.0707107.
    const Lens lens(ball_spec(10, std::sqrt(2.0)));
    IndexField f;
    f.type = IndexFieldType::SphericalN2;
    f.ior = std::sqrt(2.0);
    f.g = 0.08;
    const auto p = index_field_problems(lens, f);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].key, "");
    EXPECT_EQ(p[0].message.rfind("n = 0.848528 at (", 0), 0u) << p[0].message;
    EXPECT_NE(p[0].message.find("is below 1"), std::string::npos) << p[0].message;
    EXPECT_NE(p[0].message.find("g <= sqrt(1 - 1/ior^2) / max |x| = 0.0707107 1/mm"), std::string::npos)
        << p[0].message;
}

TEST(IndexFieldProblems, GrinRodAndLinearNBelowVacuum) {
    const Lens lens({INFINITY, INFINITY, 3, 25, 1.5});
    // radial_n2 with G = 0.07 in the window (a = 12.5): n^2 = 2.25 (1 - 0.0049 * 156.25) = 0.527344
    // on the rim, n = 0.726184; the bound is sqrt(1 - 1 / 2.25) / 12.5 = 0.745356 / 12.5 = 0.0596285.
    IndexField f;
    f.type = IndexFieldType::RadialN2;
    f.ior = 1.5;
    f.g = 0.07;
    auto p = index_field_problems(lens, f);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].message.rfind("n = 0.726184 at (", 0), 0u) << p[0].message;
    EXPECT_NE(p[0].message.find("radial_n2 keeps n >= 1 in this object for g <= sqrt(1 - 1/ior^2) / a = 0.0596285 1/mm"),
              std::string::npos)
        << p[0].message;
    // linear_n with n = 1.5 + 0.05 x: n = 1.5 - 0.625 = 0.875 on the rim at x = -12.5 (n^2 > 0 there,
    // so this is the n < 1 problem, with n itself).
    f = IndexField{};
    f.type = IndexFieldType::LinearN;
    f.gradient = {0.05, 0, 0};
    p = index_field_problems(lens, f);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].key, "");
    EXPECT_EQ(p[0].message.rfind("n = 0.875 at (-12.5, ", 0), 0u) << p[0].message;
}

TEST(IndexFieldProblems, NegativeSquaredIndexInACorner) {
    // linear_n2 over the window (a = 12.5, t = 3): n^2 = 2.25 + 0.1 x + 0.1 y + 0.5 z is lowest at
    // rho = a opposite (1, 1) and z = -1.5: 2.25 - 0.1 sqrt 2 12.5 - 0.75 = -0.267767 at
    // (-8.83883, -8.83883, -1.5).
    const Lens lens({INFINITY, INFINITY, 3, 25, 1.5});
    IndexField f;
    f.type = IndexFieldType::LinearN2;
    f.ior = 1.5;
    f.gradient = {0.1, 0.1, 0.5};
    const IndexRange r = index_range(lens, f);
    EXPECT_NEAR(r.n2_min, 1.5 - 1.25 * std::sqrt(2.0), tol::quadratic_extreme(magnitude(f.n2_form(), scale_of(lens))));
    const auto p = index_field_problems(lens, f);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].key, "");
    EXPECT_EQ(p[0].message,
              "n^2 = -0.267767 at (-8.83883, -8.83883, -1.5) mm: the index must be real everywhere in the object");
}

TEST(IndexFieldProblems, ParametersMustBeFiniteAndTheHessianSymmetric) {
    const Lens lens({50, -50, 6, 25, 1.5});
    IndexField f;
    f.ior = 1.5;
    f.type = IndexFieldType::QuadraticN2;
    f.hessian = Mat3{{0, 0.1, 0, 0.2, 0, 0, 0, 0, 0}};
    auto p = index_field_problems(lens, f);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].key, "hessian");
    EXPECT_EQ(p[0].message, "hessian[0][1] = 0.1 but hessian[1][0] = 0.2: a Hessian is symmetric");

    f.hessian = Mat3::zero();
    f.gradient = {0, NAN, 0};
    p = index_field_problems(lens, f);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].key, "gradient");

    f = IndexField{};
    f.type = IndexFieldType::SphericalN2;
    f.g = INFINITY;
    p = index_field_problems(lens, f);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].key, "g");

    // A non-finite ior (the object's) makes n^2 NaN: reported, not passed as valid.
    f = IndexField{};
    f.type = IndexFieldType::LinearN2;
    f.ior = NAN;
    p = index_field_problems(lens, f);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].message.rfind("n^2 = nan at ", 0), 0u) << p[0].message;

    // A uniform field is always valid; a gentle gradient is too (n stays near 1.5).
    EXPECT_TRUE(index_field_problems(lens, IndexField{}).empty());
    f = IndexField{};
    f.type = IndexFieldType::LinearN2;
    f.gradient = {0.001, 0, 0.002};
    EXPECT_TRUE(index_field_problems(lens, f).empty());
}
