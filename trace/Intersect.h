#pragma once
// Exact ray-surface intersections in double precision, for refining mesh hits and for the
// analytic primitives. All roots of the surface along the ray are returned, ascending.
//
// Quadrics use the stable quadratic (pbrt-v4, util/math.h Quadratic): with the discriminant in
// the "distance from the line" form, which does not cancel when the ray passes close to the
// centre, q = -(b + copysign(sqrt(disc), b)) / 2, t0 = q / a, t1 = c / q.
#include "geometry/Surface.h"

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
// cancellation-free equivalent).
Roots solve_quadratic(double a, double b, double c, double disc);

// Every intersection of the ray o + t d (d unit) with the full surface (both cone nappes, the
// whole infinite cylinder / plane). The torus's quartic roots are isolated with a guarantee
// (trace/Polynomial.h) and polished to the rounding of the quartic; a tangent ray is no hit.
Roots intersect(const Surface& s, const Vec3& o, const Vec3& d);

// A bound on how far the computed point p can be from the true surface point it represents:
// its residual distance plus the rounding of evaluating that distance (a few ulps of the
// magnitudes involved). Used to offset spawned rays (pbrt-v4's OffsetRayOrigin idea).
double point_error_bound(const Surface& s, const Vec3& p);

}  // namespace ltm
