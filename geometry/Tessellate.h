#pragma once
// Direct tessellation of analytic solids into closed, outward-oriented, tagged triangle meshes,
// each with a bound on its chord (sagitta) error: the largest distance between a face and the
// analytic surface its tag names.
#include <array>
#include <functional>
#include <vector>

#include "geometry/Lens.h"
#include "geometry/TriMesh.h"

namespace ltm {

// The point of triangle (a, b, c) closest to p (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Largest distance from face f to `s`, sampled on a barycentric grid of `n` steps per edge plus
// the exact closest-approach point for spheres. For the faces of an inscribed sphere tessellation
// the exact value is R - min_{x in face} |x - C|, which is what the sphere branch computes.
double face_deviation(const TriMesh& mesh, size_t f, const Surface& s, int n = 8);

struct LensTessellation {
    TriMesh mesh;
    int rings = 0;          // concentric rings per cap; ring i holds 6 i vertices
    int rim_rows = 0;       // rows of quads on the rim
    double chord_error = 0; // measured maximum face deviation (front, back, rim)
};

// Concentric-ring tessellation of the lens: both caps share their outer ring with the rim band.
// Ring radii are uniform in arc length on curved caps. The ring count is the smallest that keeps
// every face within `chord_tolerance` of its surface (checked exactly, face by face).
LensTessellation tessellate_lens(const Lens& lens, double chord_tolerance, int tag_front, int tag_back,
                                 int tag_rim);

// A closed ellipsoid (a sphere when the semi-axes are equal): an icosphere of the smallest level
// whose chord error, mapped through the ellipsoid's affine map, is within `chord_tolerance`.
// The map scales distances by at most max(semi_axes), so the world chord error is at most
// max(semi_axes) times the unit icosphere's. `frame` orients the body axes.
struct EllipsoidTessellation {
    TriMesh mesh;
    int level = 0;
    double chord_error_bound = 0;
};
EllipsoidTessellation tessellate_ellipsoid(const Vec3& centre, const Mat3& frame, const Vec3& semi_axes,
                                           double chord_tolerance, int tag);

// A closed solid swept by a convex planar profile (vertices counter-clockwise in its own 2D
// coordinates) through `stations` placements. `place(station, p2d)` maps a profile point at a
// station to 3D. Side faces between consecutive stations take the tag of their profile edge
// (edge i runs from vertex i to i+1); the two end caps take `tag_start` / `tag_end`. The result
// is oriented outward whatever the profile's handedness under `place`.
struct Point2 {
    double s, t;
};
TriMesh sweep_profile(const std::vector<Point2>& profile, int stations,
                      const std::function<Vec3(int, const Point2&)>& place,
                      const std::vector<int>& edge_tags, int tag_start, int tag_end);

}  // namespace ltm
