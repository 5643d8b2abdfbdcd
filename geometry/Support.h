#pragma once
// Supporting faces of a triangle mesh: a face whose plane has every vertex of the mesh on one
// side (or on the plane). A straight ray that starts strictly on the other side of such a plane
// and does not move towards it can meet no face of the mesh: every face lies in the closed
// half-space of the vertices. The mesh-only tracer asks this of every ray that leaves a face
// (Tracer::mesh_clear_ahead) and answers "nothing ahead" without a query where it holds.
//
// The answer is exact for the mesh and ray as given (for the tracer: Embree's float vertices and
// float ray): which side each vertex is on is decided exactly, and the rounding of the stored
// plane and of the test itself is bounded (SupportPlane::slack, clears_mesh).
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "geometry/TriMesh.h"

namespace ltm {

// Per face: the plane n . x = c through the face, n unit and oriented away from the mesh (every
// vertex v has n . v <= c for the exact plane through the face's vertices), rounded. `slack`
// bounds, for every point x of the mesh's bounding box, how much n . x - c (evaluated exactly)
// can exceed the exact plane's signed distance of x. n = 0, c = 0, slack = 0 where the face does
// not support the mesh (vertices on both sides) or is degenerate.
struct SupportPlane {
    Vec3 n;
    double c = 0;
    double slack = 0;
};

// Exact for the vertices as given (CGAL's exact orientation predicate where the double evaluation
// cannot decide; a k-d tree of the vertices prunes the boxes that lie wholly on the face's inner
// side by a bound on that evaluation's rounding).
std::vector<SupportPlane> supporting_planes(const TriMesh& mesh);

// True when the ray o + t d, t >= 0, meets no face of the mesh whose supporting plane s is: o lies
// beyond the plane by more than its slack plus the rounding of evaluating n . o - c (a dot product
// and a difference, at most 4 u (|n|_1 |o|_inf + |c|) with |n|_1 <= sqrt 3; 8 u (|o|_1 + |c|) covers
// it), and d does not move towards the plane (n . d computed > 4 u puts the exact value above 0:
// its rounding is at most 3 u |n| |d|). Then every point x of the ray inside the mesh's box has
// exact distance > 0 from the exact plane, and every face lies on or below that plane. False for
// a face that does not support the mesh (n = 0).
inline bool clears_mesh(const SupportPlane& s, const Vec3& o, const Vec3& d) {
    constexpr double u = std::numeric_limits<double>::epsilon() * 0.5;
    const double beyond = dot(s.n, o) - s.c;
    const double rounding = 8 * u * (std::fabs(o.x) + std::fabs(o.y) + std::fabs(o.z) + std::fabs(s.c));
    return dot(s.n, d) > 4 * u && beyond > s.slack + rounding;
}

}  // namespace ltm
