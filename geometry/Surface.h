#pragma once
// Analytic surfaces in double precision: the exact geometry that every mesh face is tagged with
// and that later stages (tracing, validation) refine hits to.
//
// Every surface is an implicit surface f(p) = 0 with an exact Euclidean distance. Orientation:
// `signed_distance` is positive on the side the surface's reference normal points to
// (outward of the sphere/cylinder/ellipsoid/torus, away from the cone axis, along a plane's
// normal). Which medium lies on which side is not a property of the surface but of its entry in
// the SurfaceTable (see SurfaceTable.h).
#include <string>

#include "geometry/Vec3.h"

namespace ltm {

enum class SurfaceKind { Plane, Sphere, Cylinder, Ellipsoid, Cone, Torus };

const char* to_string(SurfaceKind kind);

struct Surface {
    SurfaceKind kind = SurfaceKind::Plane;
    // Plane: point `origin`, unit normal `axis`.
    // Sphere: centre `origin`, `radius`.
    // Cylinder: a point `origin` on the axis, unit `axis`, `radius` (infinite along the axis).
    // Ellipsoid: centre `origin`, body axes the columns of `frame` (orthonormal), `semi_axes`.
    // Cone: apex `origin`, unit `axis`, half-angle `angle` (0 < angle < pi/2), both nappes.
    // Torus: centre `origin`, unit `axis`, major radius `radius`, minor radius `minor_radius`.
    Vec3 origin;
    Vec3 axis{0, 0, 1};
    double radius = 0;
    double minor_radius = 0;
    double angle = 0;
    Vec3 semi_axes;
    Mat3 frame;

    static Surface plane(const Vec3& point, const Vec3& normal);
    static Surface sphere(const Vec3& centre, double radius);
    static Surface cylinder(const Vec3& point_on_axis, const Vec3& axis, double radius);
    static Surface ellipsoid(const Vec3& centre, const Mat3& frame, const Vec3& semi_axes);
    static Surface cone(const Vec3& apex, const Vec3& axis, double half_angle);
    static Surface torus(const Vec3& centre, const Vec3& axis, double major, double minor);

    // Exact signed Euclidean distance (see orientation above).
    double signed_distance(const Vec3& p) const;
    // The closest point on the surface (for the cone: on the nearer nappe).
    Vec3 project(const Vec3& p) const;
    // Unit reference normal at (or near) p: the gradient direction of signed_distance.
    Vec3 normal(const Vec3& p) const;

    std::string describe() const;
};

// Closest point on an axis-aligned ellipsoid with semi-axes e (any order) to the point y, in the
// ellipsoid's body frame. Eberly, "Distance from a point to an ellipse, an ellipsoid, or a
// hyperellipsoid" (2013): the closest point is x_i = e_i^2 y_i / (t + e_i^2) where t is the unique
// root of F(t) = sum (e_i y_i / (t + e_i^2))^2 - 1 on t > -min(e)^2, found by bisection to full
// double precision. A zero coordinate of y is replaced by 1e-13 max(e), which moves the answer by
// less than that and keeps F's pole on the bracket's end.
Vec3 ellipsoid_closest_point(const Vec3& semi_axes, const Vec3& y);
// The farthest point of the same ellipsoid from y: the root of the same F on t < -max(e)^2.
Vec3 ellipsoid_farthest_point(const Vec3& semi_axes, const Vec3& y);

}  // namespace ltm
