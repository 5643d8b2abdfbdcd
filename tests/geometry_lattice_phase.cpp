// The lattice's periodic interpolation error and the end correction built on it
// (geometry/LatticePhase.h): the closed form of S against its barycentric definition on BCC's
// Delaunay tetrahedra, found here by brute force; against the interpolation error of a TetGen
// lattice mesh, through the frame the mesh records; and Psi as the periodic solution of
// (p . grad) Psi = grad e / 2 with p . Psi = e / 2.
#include "geometry/LatticePhase.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "geometry/TetMesh.h"
#include "geometry/Tessellate.h"
#include "tests/Tolerances.h"

using namespace ltm;

namespace {

double trace_of(const Mat3& a, const Mat3& b) {  // tr(A B) for symmetric B
    double t = 0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) t += a(i, j) * b(j, i);
    return t;
}

// Barycentric coordinates of x in (v0..v3).
std::array<double, 4> barycentric(const std::array<Vec3, 4>& v, const Vec3& x) {
    const Vec3 a = v[1] - v[0], b = v[2] - v[0], c = v[3] - v[0], u = x - v[0];
    const double det = dot(a, cross(b, c));
    const double l1 = dot(u, cross(b, c)) / det, l2 = dot(a, cross(u, c)) / det, l3 = dot(a, cross(b, u)) / det;
    return {1.0 - l1 - l2 - l3, l1, l2, l3};
}

// S(xi) = sum_v l_v (v - xi)(v - xi)^T over the BCC Delaunay tetrahedron holding xi, found by brute
// force: among the corners of xi's cube, its centre and the six neighbouring centres, the four
// points whose six squared distances are {1, 1, 3/4, 3/4, 3/4, 3/4} (two adjacent centres and an
// edge of the face between them: BCC's Delaunay tetrahedra) and whose hull holds xi.
Mat3 moment_by_definition(const Vec3& xi) {
    const Vec3 o{std::floor(xi.x), std::floor(xi.y), std::floor(xi.z)};
    std::vector<Vec3> pts;
    for (int i = 0; i < 8; ++i) pts.push_back(o + Vec3{double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
    const Vec3 c = o + Vec3{0.5, 0.5, 0.5};
    pts.push_back(c);
    for (int k = 0; k < 3; ++k)
        for (int s = -1; s <= 1; s += 2) {
            Vec3 d;
            d[k] = s;
            pts.push_back(c + d);
        }
    const size_t n = pts.size();
    for (size_t a = 0; a < n; ++a)
        for (size_t b = a + 1; b < n; ++b)
            for (size_t e = b + 1; e < n; ++e)
                for (size_t f = e + 1; f < n; ++f) {
                    const std::array<Vec3, 4> v{pts[a], pts[b], pts[e], pts[f]};
                    int ones = 0, threes = 0;
                    for (int i = 0; i < 4; ++i)
                        for (int j = i + 1; j < 4; ++j) {
                            const double d2 = length2(v[i] - v[j]);
                            ones += d2 == 1.0;
                            threes += d2 == 0.75;
                        }
                    if (ones != 2 || threes != 4) continue;
                    const auto l = barycentric(v, xi);
                    if (l[0] < -1e-12 || l[1] < -1e-12 || l[2] < -1e-12 || l[3] < -1e-12) continue;
                    Mat3 s = Mat3::zero();
                    for (int q = 0; q < 4; ++q) {
                        const Vec3 d = v[q] - xi;
                        for (int i = 0; i < 3; ++i)
                            for (int j = 0; j < 3; ++j) s(i, j) += l[q] * d[i] * d[j];
                    }
                    return s;
                }
    ADD_FAILURE() << "no BCC tetrahedron holds " << xi.x << " " << xi.y << " " << xi.z;
    return Mat3::zero();
}

// A general symmetric Hessian (world frame), and a bound on its norm (Gershgorin: the largest
// absolute row sum).
constexpr double kHessianNorm = 0.072;
Mat3 test_hessian() {
    Mat3 h;
    const double v[9] = {0.031, -0.012, 0.007, -0.012, -0.018, 0.021, 0.007, 0.021, 0.044};
    for (int i = 0; i < 9; ++i) h.m[i] = v[i];
    return h;
}

}  // namespace

// The closed form (B2 of the six plane families) is S's definition: they agree to rounding (the
// terms are O(1), so 1e-13 is a few hundred ulps) at random points, and S vanishes at the
// vertices, where interpolation is exact (tests/Tolerances.h).
TEST(LatticePhase, ClosedFormMomentIsTheBarycentricDefinition) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    for (int k = 0; k < 2000; ++k) {
        const Vec3 xi{u(rng), u(rng), u(rng)};
        const Mat3 a = bcc_interpolation_moment(xi), b = moment_by_definition(xi);
        for (int i = 0; i < 9; ++i)
            ASSERT_NEAR(a.m[i], b.m[i], tol::kLatticeMomentAbs) << xi.x << " " << xi.y << " " << xi.z;
    }
    for (const Vec3& v : {Vec3{0, 0, 0}, Vec3{2, -1, 5}, Vec3{0.5, 0.5, 0.5}, Vec3{-1.5, 3.5, 0.5}}) {
        const Mat3 s = bcc_interpolation_moment(v);
        for (int i = 0; i < 9; ++i) EXPECT_NEAR(s.m[i], 0.0, tol::kLatticeMomentAbs);
    }
}

// TetGen's lattice mesh interpolates n^2 = 2.25 + x^T H x / 2 with exactly the error
// (a^2 / 2) tr(H S(xi)) at points deep inside (where every tetrahedron is the lattice's), xi from
// the frame the mesh records: the frame, the tetrahedra and the closed form agree.
TEST(LatticePhase, TetGenLatticeInterpolatesWithTheClosedFormError) {
    const Mat3 h = test_hessian();
    TetRegion r;
    r.name = "lattice";
    r.boundary = tessellate_ellipsoid({0, 0, 0}, Mat3::identity(), {1, 1, 1}, 0.01, 0).mesh;  // inscribed
    r.n2 = [h](const Vec3& x) { return 2.25 + 0.5 * dot(x, h * x); };
    r.hessian_bound = [](const Vec3&, double) { return kHessianNorm; };
    r.hessian = [h](const Vec3&) { return h; };
    r.depth = [](const Vec3& x) { return 0.99 - length(x); };
    r.tolerance = 1e-4;
    const TetMesh m = tetrahedralize(r);
    ASSERT_GT(m.lattice.spacing, 0);
    const double a = m.lattice.spacing;
    const Mat3 rt = m.lattice.rotation.transposed();
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    int checked = 0;
    for (int k = 0; k < 300; ++k) {
        const Vec3 x{u(rng), u(rng), u(rng)};
        if (length(x) > 0.5) continue;
        for (size_t t = 0; t < m.num_tets(); ++t) {
            std::array<Vec3, 4> v;
            for (int i = 0; i < 4; ++i) v[i] = m.vertices[m.tets[t][i]];
            const auto l = barycentric(v, x);
            if (l[0] < 0 || l[1] < 0 || l[2] < 0 || l[3] < 0) continue;
            double interp = 0;
            for (int i = 0; i < 4; ++i) interp += l[i] * m.n2[m.tets[t][i]];
            const Vec3 xi = (rt * x - m.lattice.origin) / a;
            const Mat3 moment = m.lattice.rotation * bcc_interpolation_moment(xi) * rt;  // world frame
            const double predicted = 0.5 * a * a * trace_of(h, moment);
            // The interpolation's rounding (tests/Tolerances.h) over n^2 <= 2.3 in the unit ball.
            EXPECT_NEAR(interp - r.n2(x), predicted, tol::interpolation_rounding(2.3, 1.0, kHessianNorm))
                << "tetrahedron " << t;
            ++checked;
            break;
        }
    }
    EXPECT_GT(checked, 100);
}

// Psi solves (p . grad) Psi = grad e / 2 for e = (a^2 / 2) tr(H (S - I / 12)), and p . Psi = e / 2.
// Both are piecewise quadratic in x, so central differences are exact away from the faces (points
// closer than ten steps to a face plane are skipped) and only rounding is left
// (tests/Tolerances.h).
TEST(LatticePhase, PsiIsThePeriodicSolutionOfTheTransportEquation) {
    LatticeFrame f;
    f.rotation = rotation_from_euler_deg({12.0, -33.0, 71.0});
    f.origin = {0.31, -0.77, 1.9};
    f.spacing = 0.07;
    const LatticePhase phase(f);
    const Mat3 h = test_hessian();
    const Mat3 rt = f.rotation.transposed();
    auto e = [&](const Vec3& x) {
        Mat3 s = bcc_interpolation_moment((rt * x - f.origin) / f.spacing);
        for (int i = 0; i < 3; ++i) s(i, i) -= 1.0 / 12.0;
        return 0.5 * f.spacing * f.spacing * trace_of(h, f.rotation * s * rt);  // S in the world frame
    };
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Vec3 p = normalize(Vec3{0.2, -0.1, 1.0}) * 1.52;
    const double step = 1e-3 * f.spacing;
    const Vec3 families[6] = {{1, 1, 0}, {1, -1, 0}, {1, 0, 1}, {1, 0, -1}, {0, 1, 1}, {0, 1, -1}};
    for (const Vec3& m : families)  // none is skipped as resonant for this p
        ASSERT_GT(std::fabs(dot(m, rt * p)), LatticePhase::kResonance * std::sqrt(2.0) * length(p));
    int checked = 0;
    for (int k = 0; k < 500; ++k) {
        const Vec3 x{u(rng), u(rng), u(rng)};
        const Vec3 xi = (rt * x - f.origin) / f.spacing;
        bool near_face = false;
        for (const Vec3& m : families) {
            const double t = dot(m, xi);
            near_face |= std::fabs(t - std::round(t)) < 10.0 * step * std::sqrt(2.0) / f.spacing;
        }
        if (near_face) continue;
        const Vec3 psi = phase(x, p, h);
        // |e| <= a^2 ||H|| / 2 (tr(H (S - I / 12)) with ||S - I / 12|| < 1).
        EXPECT_NEAR(dot(p, psi), 0.5 * e(x), tol::kLatticeInvariantRelative * f.spacing * f.spacing * kHessianNorm);
        const Vec3 d = normalize(p);
        const Vec3 transport = (phase(x + d * step, p, h) - phase(x - d * step, p, h)) * (length(p) / (2.0 * step));
        for (int i = 0; i < 3; ++i) {
            Vec3 ei;
            ei[i] = 1.0;
            const double grad_e = (e(x + ei * step) - e(x - ei * step)) / (2.0 * step);
            EXPECT_NEAR(transport[i], 0.5 * grad_e, tol::kLatticeTransportRelative * f.spacing * kHessianNorm)
                << "component " << i;
        }
        ++checked;
    }
    EXPECT_GT(checked, 100);
}
