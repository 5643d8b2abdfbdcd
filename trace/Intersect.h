#pragma once
// Exact ray-surface intersections in double precision, for refining mesh hits and for the
// analytic primitives. All roots of the surface along the ray are returned, ascending.
//
// Quadrics use the stable quadratic (pbrt-v4, util/math.h Quadratic): with the discriminant in
// the "distance from the line" form, which does not cancel when the ray passes close to the
// centre, q = -(b + copysign(sqrt(disc), b)) / 2, t0 = q / a, t1 = c / q.
#include <algorithm>
#include <cmath>

#include <limits>

#include "geometry/Surface.h"
#include "trace/TraceTolerance.h"

namespace ltm {

struct Roots {
    int count = 0;
    double t[4] = {0, 0, 0, 0};
    void push(double x) {
        if (count < 4) t[count++] = x;
    }
    void sort();
};

// Roots of a t^2 + b t + c with the discriminant given separately (disc = b^2 - 4ac, or a
// cancellation-free equivalent). Inline, with the sphere and the cylinder: every segment of every
// path solves the object's patches (perf: as calls they cost 4 % of an analytic render).
inline Roots solve_quadratic(double a, double b, double c, double disc) {
    Roots r;
    if (!(disc >= 0) || a == 0) {
        if (a == 0 && b != 0) r.push(-c / b);
        return r;
    }
    const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
    const double t0 = q / a;
    const double t1 = q != 0 ? c / q : t0;
    r.push(std::min(t0, t1));
    r.push(std::max(t0, t1));
    return r;
}

// Sphere |o + t d - c|^2 = r^2 with |d| = 1: t^2 + 2 (oc.d) t + |oc|^2 - r^2 = 0. Its discriminant
// 4 (r^2 - |oc - (oc.d) d|^2) uses the distance from the centre to the line, which stays accurate
// when the ray passes near the centre and does not subtract two large squares. Ascending.
inline Roots intersect_sphere(const Vec3& c, double r, const Vec3& o, const Vec3& d) {
    const Vec3 oc = o - c;
    const double b = dot(oc, d);
    const Vec3 perp = oc - d * b;
    const double lp = length(perp), lo = length(oc);
    return solve_quadratic(1.0, 2.0 * b, (lo - r) * (lo + r), 4.0 * (r - lp) * (r + lp));
}

// Cylinder of axis (c, u) (u unit) and radius r: the same in the plane normal to the axis. Ascending.
inline Roots intersect_cylinder(const Vec3& c, const Vec3& u, double r, const Vec3& o, const Vec3& d) {
    // Project onto the plane normal to the axis: |oc_p + t d_p|^2 = r^2.
    const Vec3 oc = o - c;
    const Vec3 ocp = oc - u * dot(oc, u), dp = d - u * dot(d, u);
    const double a = dot(dp, dp);
    if (a == 0) return {};
    const double b = dot(ocp, dp);
    // Distance from the axis to the (projected) line: |ocp - (ocp.dp / a) dp|.
    const Vec3 perp = ocp - dp * (b / a);
    const double lp = length(perp), lo = length(ocp);
    return solve_quadratic(a, 2.0 * b, (lo - r) * (lo + r), 4.0 * a * (r - lp) * (r + lp));
}

// Every intersection of the ray o + t d (d unit) with the full surface (both cone nappes, the
// whole infinite cylinder / plane). The torus's quartic roots are isolated with a guarantee
// (trace/Polynomial.h) and polished to the rounding of the quartic; a tangent ray is no hit.
Roots intersect(const Surface& s, const Vec3& o, const Vec3& d);

// A bound on how far the computed point p can be from the true surface point it represents:
// its residual distance plus the rounding of evaluating that distance (a few ulps of the
// magnitudes involved). Used to offset spawned rays (pbrt-v4's OffsetRayOrigin idea).
double point_error_bound(const Surface& s, const Vec3& p);
// Its second part: the rounding of evaluating the distance, kPointErrorUlps ulps of the
// magnitudes involved (point_error_bound = |signed distance| + this).
inline double point_rounding_bound(const Surface& s, const Vec3& p) {
    constexpr double u = std::numeric_limits<double>::epsilon() * 0.5;
    const double mag = std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) +
                       std::max({std::fabs(s.origin.x), std::fabs(s.origin.y), std::fabs(s.origin.z)}) + s.radius +
                       s.minor_radius + std::max({s.semi_axes.x, s.semi_axes.y, s.semi_axes.z});
    return trace_tol::kPointErrorUlps * u * mag;
}

}  // namespace ltm
