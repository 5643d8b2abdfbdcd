// Supporting faces (geometry/Support.h): which faces have the whole mesh on one side, against
// constructions whose answer is known, and the "nothing ahead" rule against a brute-force ray
// test over every face.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <random>

#include "geometry/Lens.h"
#include "geometry/Support.h"
#include "geometry/Tessellate.h"

using namespace ltm;

namespace {

// The unit cube [0, 1]^3, faces wound outward. With `dent`, the top face is four triangles
// around its centre, pushed down to z = 1 - dent (a concave pit).
TriMesh cube(double dent = 0) {
    TriMesh m;
    for (int i = 0; i < 8; ++i) m.add_vertex({double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
    const auto quad = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
        m.add_triangle(a, b, c, 0);
        m.add_triangle(a, c, d, 0);
    };
    quad(0, 2, 3, 1);  // z = 0
    quad(0, 1, 5, 4);  // y = 0
    quad(2, 6, 7, 3);  // y = 1
    quad(0, 4, 6, 2);  // x = 0
    quad(1, 3, 7, 5);  // x = 1
    if (dent == 0) {
        quad(4, 5, 7, 6);  // z = 1
    } else {
        const std::uint32_t c = m.add_vertex({0.5, 0.5, 1 - dent});
        m.add_triangle(4, 5, c, 0);
        m.add_triangle(5, 7, c, 0);
        m.add_triangle(7, 6, c, 0);
        m.add_triangle(6, 4, c, 0);
    }
    return m;
}

// Whether o + t d, t >= 0, meets triangle f (Moller-Trumbore in double, boundary included).
bool meets(const TriMesh& m, size_t f, const Vec3& o, const Vec3& d) {
    const Vec3& a = m.vertices[m.triangles[f][0]];
    const Vec3 e1 = m.vertices[m.triangles[f][1]] - a, e2 = m.vertices[m.triangles[f][2]] - a;
    const Vec3 p = cross(d, e2);
    const double det = dot(e1, p);
    if (det == 0) return false;
    const Vec3 s = o - a;
    const double u = dot(s, p) / det;
    const Vec3 q = cross(s, e1);
    const double v = dot(d, q) / det;
    const double t = dot(e2, q) / det;
    return u >= 0 && v >= 0 && u + v <= 1 && t >= 0;
}

TEST(SupportingPlanes, EveryFaceOfACubeSupportsItWithItsOutwardNormal) {
    const TriMesh m = cube();
    const std::vector<SupportPlane> s = supporting_planes(m);
    ASSERT_EQ(s.size(), m.num_triangles());
    for (size_t f = 0; f < s.size(); ++f) {
        // Axis-aligned faces: the normal is exact, and c is the face's coordinate (0 or 1).
        const Vec3 expect = m.face_normal(f);
        EXPECT_EQ(s[f].n.x, expect.x) << f;
        EXPECT_EQ(s[f].n.y, expect.y) << f;
        EXPECT_EQ(s[f].n.z, expect.z) << f;
        EXPECT_EQ(s[f].c, dot(expect, m.vertices[m.triangles[f][0]])) << f;
        EXPECT_GT(s[f].slack, 0) << f;
        EXPECT_LT(s[f].slack, 1e-13) << f;  // 16 u ((kappa + 1) sqrt 3 + |a|_1), kappa <= sqrt 2
    }
}

TEST(SupportingPlanes, ThePitsFacesDoNotSupportTheMeshTheOthersDo) {
    const TriMesh m = cube(0.1);
    const std::vector<SupportPlane> s = supporting_planes(m);
    // Faces 0-9 are the five flat sides: every vertex, the pit's bottom included (z = 0.9 inside
    // the cube), is on or inside their planes. The pit's faces slope down to the centre, so the
    // far top corners lie above each of their planes and the bottom corners below.
    for (size_t f = 0; f < 10; ++f) EXPECT_EQ(s[f].n.x * s[f].n.x + s[f].n.y * s[f].n.y + s[f].n.z * s[f].n.z, 1) << f;
    for (size_t f = 10; f < 14; ++f) {
        EXPECT_EQ(s[f].n.x, 0) << f;
        EXPECT_EQ(s[f].n.y, 0) << f;
        EXPECT_EQ(s[f].n.z, 0) << f;
        EXPECT_EQ(s[f].c, 0) << f;
    }
}

TEST(SupportingPlanes, AFaceWithCollinearVerticesSupportsNothing) {
    TriMesh m = cube();
    const std::uint32_t mid = m.add_vertex({0.5, 0, 0});
    m.add_triangle(0, mid, 1, 0);  // a sliver of zero area along the edge 0-1
    const std::vector<SupportPlane> s = supporting_planes(m);
    const SupportPlane& z = s.back();
    EXPECT_EQ(z.n.x, 0);
    EXPECT_EQ(z.n.y, 0);
    EXPECT_EQ(z.n.z, 0);
    const Vec3 o{0.5, -1, 0}, d{0, -1, 0};
    EXPECT_FALSE(clears_mesh(z, o, d));
}

// A double-convex lens's tessellation: every vertex lies on a convex surface and every face within
// the chord error e of it, so no vertex lies more than 2 e beyond any face's plane (the face's
// own surface patch bulges at most e past it, the face may sit e inside the surface); a face the
// predicate calls supporting has no vertex beyond its plane at all (checked in double, beyond
// the rounding of a dot product of coordinates ~L: 1e-12 L). A non-supporting face has a vertex
// beyond, by at most 2 e.
TEST(SupportingPlanes, ALensTessellationAgreesWithBruteForce) {
    const Lens lens({50, -50, 6, 25, 1.5168});
    const LensTessellation t = tessellate_lens(lens, 1e-3, 0, 1, 2);
    const TriMesh& m = t.mesh;
    const std::vector<SupportPlane> s = supporting_planes(m);
    const double L = 25;
    size_t supporting = 0;
    for (size_t f = 0; f < m.num_triangles(); ++f) {
        const Vec3& a = m.vertices[m.triangles[f][0]];
        const Vec3 n = m.face_normal(f);  // outward: the lens is convex
        double most = -INFINITY;
        for (const Vec3& v : m.vertices) most = std::max(most, dot(n, v - a));
        ASSERT_LE(most, 2 * t.chord_error + 1e-12 * L) << f;
        const bool sup = s[f].n.x != 0 || s[f].n.y != 0 || s[f].n.z != 0;
        if (sup) {
            ++supporting;
            EXPECT_LE(most, 1e-12 * L) << f;
            EXPECT_GT(dot(s[f].n, n), 1 - 1e-12) << f;  // away from a convex mesh is outward
            EXPECT_LT(s[f].slack, 1e-9 * L) << f;
        } else {
            EXPECT_GT(most, -1e-12 * L) << f;  // some vertex is beyond (or within rounding of) it
        }
    }
    EXPECT_GT(supporting, 0u);
}

// The faces are tested in parallel on the caller's task arena (so `--threads` bounds the set-up):
// on one thread and on several, every plane is the same, bit for bit.
TEST(SupportingPlanes, OneThreadAndSeveralGiveTheSamePlanes) {
    const Lens lens({50, -50, 6, 25, 1.5168});
    const TriMesh m = tessellate_lens(lens, 1e-3, 0, 1, 2).mesh;
    ASSERT_GT(m.num_triangles(), 4 * 1024u);  // several of the parallel loop's ranges
    std::vector<SupportPlane> one, many;
    tbb::task_arena(1).execute([&] { one = supporting_planes(m); });
    tbb::task_arena(4).execute([&] { many = supporting_planes(m); });
    ASSERT_EQ(one.size(), many.size());
    for (size_t f = 0; f < one.size(); ++f) {
        EXPECT_EQ(std::memcmp(&one[f], &many[f], sizeof(SupportPlane)), 0) << f;
    }
}

// The rule itself: from a point of a supporting face moved a little beyond its plane, every
// direction that does not point back meets no face (brute force over all of them); moved inside,
// or pointing back, the rule does not apply. The offsets are 1e-9 L: the tracer's spawned rays
// sit 8 float ulps (~1e-6 of their coordinates) off the face, and the rule's slack is ~1e-14 L.
TEST(SupportingPlanes, ARayBeyondASupportingFaceMeetsNothing) {
    const Lens lens({50, -50, 6, 25, 1.5168});
    const TriMesh m = tessellate_lens(lens, 1e-2, 0, 1, 2).mesh;
    const std::vector<SupportPlane> s = supporting_planes(m);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uni(0, 1);
    const double L = 25, delta = 1e-9 * L;
    int checked = 0;
    for (size_t f = 0; f < m.num_triangles(); f += 7) {
        const SupportPlane& p = s[f];
        if (p.n.x == 0 && p.n.y == 0 && p.n.z == 0) continue;
        double b1 = uni(rng), b2 = uni(rng);
        if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
        const auto& tri = m.triangles[f];
        const Vec3 x = m.vertices[tri[0]] * (1 - b1 - b2) + m.vertices[tri[1]] * b1 + m.vertices[tri[2]] * b2;
        Vec3 d{uni(rng) * 2 - 1, uni(rng) * 2 - 1, uni(rng) * 2 - 1};
        d = normalize(d);
        if (dot(d, p.n) < 0) d = -d;
        const Vec3 out = x + p.n * delta;
        EXPECT_TRUE(clears_mesh(p, out, d)) << f;
        EXPECT_TRUE(clears_mesh(p, out, p.n)) << f;
        for (size_t g = 0; g < m.num_triangles(); ++g) {
            ASSERT_FALSE(meets(m, g, out, d)) << f << " " << g;
            ASSERT_FALSE(meets(m, g, out, p.n)) << f << " " << g;
        }
        EXPECT_FALSE(clears_mesh(p, x - p.n * delta, d)) << f;   // inside the glass
        EXPECT_FALSE(clears_mesh(p, out, -d)) << f;              // heading back
        ++checked;
    }
    EXPECT_GT(checked, 10);
}

}  // namespace
