// The analytic lens against independent derivations, and its tessellation's invariants for every
// sign combination of radii and for windows, across scales.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "geometry/Boolean.h"
#include "geometry/Lens.h"
#include "geometry/Tessellate.h"
#include "tests/Tolerances.h"

using namespace ltm;

namespace {

struct Kind {
    const char* name;
    LensSpec spec;
};

// Every sign combination the conventions name, at the paper's size (D = 25 mm).
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
    };
}

// Gauss-Legendre rule on [0, 1] with n nodes (Newton on P_n; Numerical Recipes' gauleg).
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
    x.resize(n);
    w.resize(n);
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), pp = 0;
        for (int it = 0; it < 100; ++it) {
            double p1 = 1, p2 = 0;
            for (int j = 0; j < n; ++j) {
                const double p3 = p2;
                p2 = p1;
                p1 = ((2 * j + 1) * z * p2 - j * p3) / (j + 1);
            }
            pp = n * (z * p1 - p2) / (z * z - 1);
            const double z1 = z;
            z = z1 - p1 / pp;
            if (std::fabs(z - z1) < 1e-16) break;
        }
        x[i] = 0.5 * (1 - z);
        x[n - 1 - i] = 0.5 * (1 + z);
        w[i] = w[n - 1 - i] = 1.0 / ((1 - z * z) * pp * pp);
    }
}

}  // namespace

TEST(Lens, SagIsStableForFlatSurfaces) {
    // sag = R - sqrt(R^2 - rho^2) = rho^2 / (2R) + rho^4 / (8 R^3) + ...; at R = 1e8, rho = 1 the
    // series is exact to 1e-32 relative, while the textbook difference would lose 16 digits.
    const double R = 1e8, rho = 1.0;
    EXPECT_NEAR(sphere_sag(R, rho), rho * rho / (2 * R) + std::pow(rho, 4) / (8 * R * R * R), 4 * tol::kEps * 5e-9);
    EXPECT_EQ(sphere_sag(INFINITY, 3.0), 0.0);
    EXPECT_DOUBLE_EQ(sphere_sag(-5.0, 5.0), -5.0);  // a hemisphere's rim lies R from its vertex
}

TEST(Lens, VolumeMatchesClosedFormsAndQuadrature) {
    // Hemisphere (r1 = a) on a cylinder of height 1: V = 2/3 pi a^3 + pi a^2 (t - a).
    const Lens h({5.0, INFINITY, 6.0, 10.0, 1.5});
    EXPECT_NEAR(h.volume(), 2.0 / 3.0 * kPi * 125 + kPi * 25 * 1.0,
                tol::lens_volume(kPi * 25 * 6.0 + 2.0 / 3.0 * kPi * 125));
    EXPECT_NEAR(h.front_area(), 2 * kPi * 25, tol::cap_area(2 * kPi * 25));  // hemisphere: 2 pi a^2
    // Every kind: V = int_0^a (z_back - z_front) 2 pi rho d rho by 64-point Gauss-Legendre (the
    // integrand is analytic on [0, a] for |R| > a; the rule is exact to double precision).
    std::vector<double> x, w;
    gauss_legendre(64, x, w);
    for (const auto& k : lens_kinds()) {
        const Lens lens(k.spec);
        const double a = lens.aperture_radius();
        double v = 0;
        for (size_t i = 0; i < x.size(); ++i) {
            const double rho = a * x[i];
            v += w[i] * a * (lens.z_back(rho) - lens.z_front(rho)) * 2 * kPi * rho;
        }
        EXPECT_NEAR(lens.volume(), v, tol::quadrature_volume_relative() * v) << k.name;
    }
}

TEST(Lens, RejectsImpossibleGeometry) {
    auto first_key = [](LensSpec s) {
        const auto p = Lens::problems(s);
        return p.empty() ? std::string("none") : p.front().key;
    };
    EXPECT_EQ(first_key({10, -50, 6, 25, 1.5}), "r1");          // |R| < D/2
    EXPECT_EQ(first_key({50, -50, 1, 25, 1.5}), "center_thickness");  // edge thickness < 0
    EXPECT_EQ(first_key({50, -50, 6, 25, 1.0}), "ior");
    EXPECT_EQ(first_key({50, -50, -6, 25, 1.5}), "center_thickness");
    EXPECT_EQ(first_key({50, -50, 6, 0, 1.5}), "diameter");
    EXPECT_EQ(first_key({50, -50, 6, 25, 1.5}), "none");
    EXPECT_THROW(Lens({10, -50, 6, 25, 1.5}), std::invalid_argument);
}

TEST(Lens, PatchDistancesAreExact) {
    const Lens lens({50, -50, 6, 25, 1.5});
    // On the axis the front vertex is 3 mm below the centre; the rim is 12.5 mm away.
    EXPECT_NEAR(lens.distance_to_front({0, 0, 0}), 3.0, tol::exact_operands(3.0));
    EXPECT_NEAR(lens.distance_to_rim({0, 0, 0}), 12.5, tol::exact_operands(12.5));
    EXPECT_NEAR(lens.signed_distance({0, 0, 0}), 3.0, tol::exact_operands(3.0));
    EXPECT_LT(lens.signed_distance({0, 0, 10}), 0.0);
    // Outside the aperture the nearest cap point is its edge circle.
    const double ze = lens.z_front(12.5);
    EXPECT_NEAR(lens.distance_to_front({15.5, 0, ze - 4}), 5.0, tol::cap_edge_distance(std::fabs(ze) + 4.0 + 5.0));
}

// The farthest point of the solid from p (Lens::farthest_distance) against independent references.
// Closed forms: a ball of radius R is |p| + R from p at its farthest (the antipode); a window, the
// cylinder rho <= a, |z| <= t/2, is hypot(rho + a, |z| + t/2) (the rim's far edge on the far face).
// Every kind: the largest distance to a sampling of the boundary (the caps over a polar grid, the
// rim over z and azimuth) is a lower bound, at most the sampling's covering radius h below the
// exact value (distance is 1-Lipschitz). The points are chosen so that a wrong branch (a cap's
// edge instead of its interior antipode, or the reverse) is off by far more than h.
TEST(Lens, FarthestDistanceIsExact) {
    const std::vector<Vec3> points = {{0, 0, 0},    {0, 0, -200},   {0, 0, 200},  {30, 5, -4},  {-3, 2, 60},
                                      {100, -50, 0}, {5, 5, -47},   {1, -2, 47},  {0.5, 0, -3}, {12.5, 0, 1}};
    const double R = 12.5;
    const Lens ball(ball_spec(R, 1.5));
    for (const Vec3& p : points)
        EXPECT_NEAR(ball.farthest_distance(p), length(p) + R, tol::farthest_point(length(p) + R)) << p.x << " " << p.y << " " << p.z;
    const Lens window({INFINITY, INFINITY, 3, 25, 1.5});
    for (const Vec3& p : points) {
        const double expected = std::hypot(std::hypot(p.x, p.y) + 12.5, std::fabs(p.z) + 1.5);
        EXPECT_NEAR(window.farthest_distance(p), expected, tol::farthest_point(expected)) << p.x << " " << p.y << " " << p.z;
    }
    const int n_rho = 100, n_phi = 720, n_z = 50;
    for (const Kind& k : lens_kinds()) {
        const Lens lens(k.spec);
        const double a = lens.aperture_radius();
        // Neighbouring samples of a cap are at most dr |R| / sqrt(R^2 - a^2) apart along a meridian
        // (the arc over a radial step, steepest at the rim) and a dphi apart along a parallel, the
        // rim's dz and a dphi: half the diagonal of the coarser cell bounds the covering radius.
        const double dr = a / n_rho, dphi = 2 * kPi / n_phi;
        double h = 0.5 * std::hypot(lens.edge_thickness() / n_z, a * dphi);
        for (double Rf : {k.spec.r1, k.spec.r2})
            h = std::max(h, 0.5 * std::hypot(std::isinf(Rf) ? dr : dr * std::fabs(Rf) / std::sqrt(Rf * Rf - a * a), a * dphi));
        for (const Vec3& p : points) {
            double sampled = 0;
            for (int j = 0; j < n_phi; ++j) {
                const double c = std::cos(j * dphi), s = std::sin(j * dphi);
                for (int side = 0; side < 2; ++side)
                    for (int i = 0; i <= n_rho; ++i)
                        sampled = std::max(sampled, distance(p, lens.surface_point(side, i * dr * c, i * dr * s)));
                for (int i = 0; i <= n_z; ++i) {
                    const double z = lens.z_front(a) + lens.edge_thickness() * i / n_z;
                    sampled = std::max(sampled, distance(p, Vec3{a * c, a * s, z}));
                }
            }
            const double exact = lens.farthest_distance(p);
            EXPECT_GE(exact, sampled - tol::farthest_point(sampled)) << k.name << " " << p.x << " " << p.y << " " << p.z;
            EXPECT_LE(exact, sampled + h) << k.name << " " << p.x << " " << p.y << " " << p.z;
        }
    }
}

class LensTessellationTest : public ::testing::TestWithParam<std::tuple<int, double, double>> {};

// For each kind, chord tolerance and scale: a closed, manifold, outward, self-intersection-free
// genus-0 mesh whose vertices lie on their surfaces, whose faces are within the tolerance of
// their tagged surface and whose volume is within tolerance x area of the analytic volume.
TEST_P(LensTessellationTest, Invariants) {
    const auto [kind_index, tolerance_rel, scale] = GetParam();
    Kind kind = lens_kinds()[kind_index];
    LensSpec s = kind.spec;
    s.r1 *= scale; s.r2 *= scale; s.center_thickness *= scale; s.diameter *= scale;
    const Lens lens(s);
    const double tol = tolerance_rel * scale;
    const LensTessellation t = tessellate_lens(lens, tol, 0, 1, 2);
    const TriMesh& m = t.mesh;
    SCOPED_TRACE(kind.name);

    const SolidCheck c = check_solid(m);
    EXPECT_TRUE(c.ok()) << "closed " << c.closed << " nm " << c.non_manifold_vertices << " si " << c.self_intersecting
                        << " vol " << c.bounds_volume;
    EXPECT_EQ(c.components, 1u);
    // Euler characteristic of a sphere: V - E + F = 2 with E = 3F/2.
    EXPECT_EQ(static_cast<long>(m.num_vertices()) - static_cast<long>(3 * m.num_triangles() / 2) +
                  static_cast<long>(m.num_triangles()), 2);

    const Surface surf[3] = {lens.front_surface(), lens.back_surface(), lens.rim_surface()};
    const int sign[3] = {lens.front_normal_sign(), lens.back_normal_sign(), +1};
    const double L = std::max(s.diameter, s.center_thickness) + std::fabs(lens.z_front(lens.aperture_radius()));
    for (size_t f = 0; f < m.num_triangles(); ++f) {
        const int tag = m.tags[f];
        for (int k = 0; k < 3; ++k)
            ASSERT_LE(std::fabs(surf[tag].signed_distance(m.vertices[m.triangles[f][k]])), tol::on_surface(L))
                << "face " << f;
        // Spheres: face_deviation adds the exact closest approach; a coarse grid covers the rest.
        ASSERT_LE(face_deviation(m, f, surf[tag], 2), tol + tol::on_surface(L)) << "face " << f;
        // Outward: the face normal agrees with the analytic outward normal at the centroid.
        const auto& tr = m.triangles[f];
        const Vec3 cen = (m.vertices[tr[0]] + m.vertices[tr[1]] + m.vertices[tr[2]]) / 3.0;
        ASSERT_GT(dot(m.face_normal(f), surf[tag].normal(cen) * double(sign[tag])), 0.9) << "face " << f;
    }
    const double area = lens.front_area() + lens.back_area() + lens.rim_area();
    EXPECT_NEAR(m.signed_volume(), lens.volume(), tol::volume_bound(t.chord_error, area, 0.0));
    EXPECT_NEAR(c.volume, lens.volume(), tol::volume_bound(t.chord_error, area, 0.0));
    EXPECT_LE(t.chord_error, tol);
}

INSTANTIATE_TEST_SUITE_P(AllKinds, LensTessellationTest,
                         ::testing::Combine(::testing::Range(0, 8), ::testing::Values(1e-2, 1e-3),
                                            ::testing::Values(1.0)));
INSTANTIATE_TEST_SUITE_P(Scales, LensTessellationTest,
                         ::testing::Combine(::testing::Values(0, 4, 6), ::testing::Values(1e-3),
                                            ::testing::Values(1e-4, 1e2)));

TEST(LensTessellation, ApexIsAVertexAndRingsMatchTheFormula) {
    // Ring i holds 6 i vertices: V = 2 (1 + 3 n (n + 1)) + 6 n (rows - 1) for two caps and the rim.
    const Lens lens({50, -50, 6, 25, 1.5168});
    const LensTessellation t = tessellate_lens(lens, 1e-3, 0, 1, 2);
    const long n = t.rings;
    EXPECT_EQ(static_cast<long>(t.mesh.num_vertices()), 2 * (1 + 3 * n * (n + 1)) + 6 * n * (t.rim_rows - 1));
    EXPECT_EQ(t.mesh.vertices[0].x, 0.0);
    EXPECT_EQ(t.mesh.vertices[0].z, -3.0);
}
