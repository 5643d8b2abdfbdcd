#pragma once
// Defect models: what can be wrong with the glass. Each is an analytic shape; DefectSolid.h turns
// it into tagged analytic surfaces and a tool mesh, SolidBuilder.h subtracts it from the object.
//
// Bubble: an air void, a sphere or an oriented ellipsoid. Enclosed unless `surface_breaking`,
//   in which case it must cross the glass boundary and becomes an open pit.
// Scratch: a groove of `width` and `depth` (mm) with a V or U cross-section, cut into the front or
//   back face along a path on that face: a straight scratch follows the face's geodesic between
//   two points (a great circle on a sphere, a segment on a plane); an arc scratch follows the
//   circle of points at 3D distance `radius` from a centre point on the face. The V profile is a
//   triangle with its apex at `depth`; the U profile is a circular arc bottom (radius
//   (w^2/4 + d^2) / (2 d) when d <= w/2; a semicircle of radius w/2 under straight walls when
//   d > w/2). Ends are flat, perpendicular to the path.
// Particle: an opaque absorbing inclusion (sphere or ellipsoid) strictly inside the glass, kept as
//   its own closed component of the mesh.
// Inhomogeneity: a local change of the glass's index inside a sphere or ellipsoid (defects/Inclusion.h):
//   smooth:  n = n_glass + delta_n (1 - rho^2)^2 for rho < 1 (C1 at rho = 1: no interface); the
//            region is meshed by TetGen and traced through its tetrahedra;
//   uniform: n = n_glass + delta_n inside, a sharp interface on the exact ellipsoid (Fresnel, Snell).
//   rho = |x - center| / radius (the body-frame ellipsoidal radius for semi_axes).
#include <string>

#include "geometry/Vec3.h"

namespace ltm {

enum class DefectType { Bubble, Scratch, Particle, Inhomogeneity };
enum class IndexProfile { Smooth, Uniform };
enum class ScratchProfile { V, U };
const char* to_string(DefectType t);

struct Defect {
    DefectType type = DefectType::Bubble;

    // Bubble, Particle, Inhomogeneity: an ellipsoid with body axes the columns of `frame`.
    Vec3 center;
    Vec3 semi_axes{0.1, 0.1, 0.1};
    Mat3 frame;
    // The Euler angles (degrees) `frame` was made from, if any (set_rotation_deg): a scene file
    // written for this defect (scene/SceneYaml.h) gives them back, and reading it rebuilds the
    // same frame bit for bit. Without them the frame is the identity.
    bool rotation_given = false;
    Vec3 rotation_deg;
    bool surface_breaking = false;  // Bubble only

    // Inhomogeneity.
    double delta_n = 0;             // peak change of n (may be negative, never 0)
    IndexProfile index_profile = IndexProfile::Smooth;

    // Scratch.
    int side = 0;                   // 0: front face, 1: back face
    bool arc = false;
    Vec3 start, end;                // straight: end points (x, y used; z checked if given)
    bool start_has_z = false, end_has_z = false;
    Vec3 arc_center;                // arc: centre point (x, y; z checked if given)
    bool arc_center_has_z = false;
    double arc_radius = 0;          // mm, 3D distance from the centre point
    double start_angle = 0, end_angle = 0;  // degrees, right-handed about +z from +x
    double width = 0.05, depth = 0.02;
    ScratchProfile profile = ScratchProfile::V;

    // Orients the ellipsoid: frame = rotation_from_euler_deg(angles_deg) (geometry/Vec3.h), and
    // records the angles. The one way to turn a defect that a scene file can reproduce.
    void set_rotation_deg(const Vec3& angles_deg) {
        rotation_given = true;
        rotation_deg = angles_deg;
        frame = rotation_from_euler_deg(angles_deg);
    }

    bool is_ellipsoid() const { return type != DefectType::Scratch; }
    bool is_sphere() const { return semi_axes.x == semi_axes.y && semi_axes.y == semi_axes.z; }
    double max_semi_axis() const;
    // The smallest ellipsoidal radius squared, rho^2 = |S^-1 F^T (x - center)|^2 (F = frame,
    // S = diag(semi_axes)), over the segment [a, b]. rho^2 is a quadratic in the segment's
    // parameter t, minimal at its vertex t* = -(u . v) / (v . v) with u, v the scaled images of
    // a - center and b - a; t* is clamped to [0, 1]. rho^2 < 1: the segment enters the ellipsoid.
    double segment_min_rho2(const Vec3& a, const Vec3& b) const;
};

}  // namespace ltm
