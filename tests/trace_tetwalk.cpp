// Paths through TetGen meshes (trace/TetWalk.h): exact parabolas tetrahedron by tetrahedron,
// checked where the interpolated field IS the exact field (n^2 constant or linear in x: linear
// interpolation reproduces it, so the walk must follow the exact line or parabola to rounding,
// whatever the mesh), through mesh vertices and edges (the walk passes them in zero-length steps,
// never stuck, never out of the region), and with |p|^2 = n^2 held along the way.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/Tessellate.h"
#include "tests/Tolerances.h"
#include "trace/Polynomial.h"
#include "trace/TetWalk.h"

using namespace ltm;

namespace {

constexpr double kU = 0x1p-53;
constexpr double kR = 2.0;  // the region: a ball of radius 2 about the origin, in a box of +-2.2

// A TetGen mesh of the ball (circumscribed by 10 %) with the field n2.
TetMesh ball_mesh(std::function<double(const Vec3&)> n2, double hessian, double tolerance) {
    TetRegion r;
    r.name = "test ball";
    r.boundary = tessellate_ellipsoid({0, 0, 0}, Mat3::identity(), {1.1 * kR, 1.1 * kR, 1.1 * kR}, 0.01, 0).mesh;
    r.n2 = std::move(n2);
    r.hessian_bound = [hessian](const Vec3&, double) { return hessian; };
    r.tolerance = tolerance;
    r.depth = [](const Vec3& x) { return 1.1 * kR * 0.99 - length(x); };
    return tetrahedralize(r);
}

// The exact sphere of radius kR as the one surface of the walk.
std::vector<Patch> sphere_surface() {
    Patch p;
    p.kind = Patch::Kind::Closed;
    p.surface = Surface::sphere({0, 0, 0}, kR);
    p.tag = 7;
    p.bounds = {{-kR, -kR, -kR}, {kR, kR, kR}};
    p.finalize();
    return {p};
}

}  // namespace

TEST(TetWalk, ConstantFieldPathsAreStraightThroughVerticesAndEdges) {
    // n^2 = 2.25 everywhere: g = 0 in every tetrahedron, the path is the straight line from its
    // start, and it meets the sphere where the line does (the stable quadratic, in the test).
    const TetMesh m = ball_mesh([](const Vec3&) { return 2.25; }, 0.0, 1e-3);
    const TetWalk w(m, sphere_surface());
    std::mt19937_64 gen(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int walks = 0, through_vertices = 0;
    // Start at the centre and aim exactly at mesh vertices (the path runs through one) and at
    // edge midpoints (through an edge).
    for (size_t t = 0; t < m.tets.size() && walks < 2000; ++t) {
        const auto& v = m.tets[t];
        for (int k = 0; k < 2; ++k) {
            const Vec3 target = k == 0 ? m.vertices[v[0]] : (m.vertices[v[1]] + m.vertices[v[2]]) * 0.5;
            if (length(target) > 0.9 * kR || length(target) < 0.1) continue;
            const Vec3 start = target * 0.25;  // on the same line through the centre
            const Vec3 d = normalize(target - start);
            const int tet = w.locate(start);
            ASSERT_GE(tet, 0);
            const TetWalk::Exit ex = w.walk(start, d * 1.5, tet, true);
            ASSERT_EQ(ex.kind, TetWalk::Exit::Kind::Surface) << "walk " << walks;
            // The line meets |x| = R at s = -b + sqrt(b^2 - c), b = start . d, c = |start|^2 - R^2.
            const double b = dot(start, d), c = length2(start) - kR * kR;
            const double s = -b + std::sqrt(b * b - c);
            const Vec3 exact = start + d * s;
            // Each crossing moves the point by ~4 rounded operations of magnitude <= R (r += p tau):
            // within 8 u R per crossing, with the exact surface's root within 64 u R.
            EXPECT_LT(distance(ex.r, exact), (8.0 * (ex.crossings + 1) + 64.0) * kU * kR) << walks;
            // |p| = n = 1.5 throughout; the arc length is the chord.
            EXPECT_NEAR(length(ex.p), 1.5, 8.0 * (ex.crossings + 1) * kU * 1.5);
            EXPECT_NEAR(ex.arc, s, (8.0 * (ex.crossings + 1) + 64.0) * kU * kR * 1.5);
            ++walks;
            through_vertices += k == 0;
        }
    }
    EXPECT_GT(walks, 500);
    EXPECT_GT(through_vertices, 200);
}

TEST(TetWalk, LinearFieldPathsAreExactParabolas) {
    // n^2 = 2.25 + g . x is linear, so its interpolant over any tetrahedron is exact and the walk
    // follows r = r0 + p0 tau + g tau^2 / 4 (GrinPath.h) to rounding, through every tetrahedron.
    // The exit tau solves |r(tau)|^2 = R^2, a quartic (solved here with trace/Polynomial.h on the
    // closed form's coefficients).
    const Vec3 g{0.05, -0.03, 0.02};
    const TetMesh m = ball_mesh([g](const Vec3& x) { return 2.25 + dot(g, x); }, 0.0, 1e-3);
    const TetWalk w(m, sphere_surface());
    std::mt19937_64 gen(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < 300; ++k) {
        Vec3 r0{u(gen), u(gen), u(gen)};
        r0 = r0 * (0.5 * kR / std::max(1.0, length(r0)));
        const Vec3 d = normalize(Vec3{u(gen), u(gen), u(gen)});
        const Vec3 p0 = d * std::sqrt(2.25 + dot(g, r0));
        const int tet = w.locate(r0);
        ASSERT_GE(tet, 0);
        const TetWalk::Exit ex = w.walk(r0, p0, tet, false);
        ASSERT_EQ(ex.kind, TetWalk::Exit::Kind::Surface) << k;
        // |r0 + p0 t + w t^2|^2 - R^2, w = g / 4.
        const Vec3 wq = g * 0.25;
        const double c[5] = {length2(r0) - kR * kR, 2 * dot(r0, p0), length2(p0) + 2 * dot(r0, wq), 2 * dot(p0, wq),
                             length2(wq)};
        const PolyRoots roots = real_roots(c, 4, 0.0, 100.0);
        ASSERT_GE(roots.count, 1);
        const double t = roots.x[0];
        const Vec3 exact = r0 + p0 * t + wq * (t * t);
        // The walk's point accumulates ~8 u |r| per crossing (r += p tau + g tau^2 / 4) plus the
        // final root's 64 u R; the closed form's own quartic root, 64 u R more.
        EXPECT_LT(distance(ex.r, exact), (8.0 * (ex.crossings + 1) + 128.0) * kU * kR * 2) << k;
        // The Hamiltonian |p|^2 - n^2: 0 at the start, conserved exactly in every tetrahedron.
        EXPECT_LT(std::fabs(length2(ex.p) - (2.25 + dot(g, ex.r))), 16.0 * (ex.crossings + 1) * kU * 2.5) << k;
    }
}

TEST(TetWalk, LocatesEveryPointOfTheRegion) {
    const TetMesh m = ball_mesh([](const Vec3& x) { return 2.25 + 0.01 * length2(x); }, 0.02, 1e-3);
    const TetWalk w(m, sphere_surface());
    std::mt19937_64 gen(2);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < 5000; ++k) {
        const Vec3 x = Vec3{u(gen), u(gen), u(gen)} * (kR / std::sqrt(3.0));
        const int t = w.locate(x);
        ASSERT_GE(t, 0) << k;
        // The located tetrahedron contains x: interpolation there is the barycentric blend, within
        // the tolerance of the field.
        EXPECT_LT(std::fabs(w.n2(t, x) - (2.25 + 0.01 * length2(x))), 1e-3 + 64 * kU * 2.3);
    }
    EXPECT_EQ(w.locate({0, 0, 5 * kR}), -1);
}
