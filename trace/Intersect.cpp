#include "trace/Intersect.h"

#include "trace/Polynomial.h"
#include "trace/TraceTolerance.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ltm {

void Roots::sort() {
    for (int i = 1; i < count && i < 4; ++i)
        for (int j = i; j > 0 && t[j - 1] > t[j]; --j) std::swap(t[j - 1], t[j]);
}

namespace {

Roots ellipsoid(const Surface& s, const Vec3& o, const Vec3& d) {
    // In the body frame scaled to the unit sphere: o' = S^-1 R^T (o - c), d' = S^-1 R^T d.
    const Mat3 rt = s.frame.transposed();
    const Vec3 ob = rt * (o - s.origin), db = rt * d;
    const Vec3 os{ob.x / s.semi_axes.x, ob.y / s.semi_axes.y, ob.z / s.semi_axes.z};
    const Vec3 ds{db.x / s.semi_axes.x, db.y / s.semi_axes.y, db.z / s.semi_axes.z};
    const double a = dot(ds, ds), b = dot(os, ds);
    const Vec3 perp = os - ds * (b / a);
    const double lp = length(perp), lo = length(os);
    return solve_quadratic(a, 2.0 * b, (lo - 1.0) * (lo + 1.0), 4.0 * a * (1.0 - lp) * (1.0 + lp));
}

// Double cone with apex A, axis u, half-angle al: (v.u)^2 = cos^2(al) |v|^2 with v = o + t d - A.
Roots cone(const Surface& s, const Vec3& o, const Vec3& d) {
    const Vec3 v = o - s.origin;
    const double c2 = std::cos(s.angle) * std::cos(s.angle);
    const double du = dot(d, s.axis), vu = dot(v, s.axis);
    const double a = du * du - c2;
    const double b = 2.0 * (du * vu - c2 * dot(d, v));
    const double c = vu * vu - c2 * dot(v, v);
    return solve_quadratic(a, b, c, b * b - 4.0 * a * c);
}

// Torus with centre C, unit axis a, radii R (major) and r (minor):
//   f(x) = (|x|^2 + R^2 - r^2)^2 - 4 R^2 (|x|^2 - (x.a)^2) = 0,  x relative to C.
// Along the ray, x = p + s d with p the ray's point nearest C (s = t - tm, so p.d = 0 and |p| is
// at most R + r wherever the ray meets the torus: the quartic's coefficients stay of the size of
// the torus and do not cancel). With dd = d.d, pa = p.a, da = d.a, A = |p|^2 + R^2 - r^2:
//   f = dd^2 s^4 + (2 dd A - 4 R^2 (dd - da^2)) s^2 + 8 R^2 pa da s + A^2 - 4 R^2 (|p|^2 - pa^2)
// (the odd terms of |x|^2 vanish with p.d = 0). Its real roots in the bounding sphere's span are
// isolated with a guarantee (trace/Polynomial.h: critical-point recursion, safeguarded Newton),
// so every sign change of the COMPUTED quartic is found; a tangent ray (a double root) is no hit.
// Near the tube f = (dist^2 - r^2)(... ~ 4 R^2) ~ 8 R^2 r s_n for a normal offset s_n, and f is
// evaluated to a few ulps of A^2, so the roots are accurate to ~eps A^2 / (8 R^2 r).
// That rounding (c0 and c2 cancel: ~eps (R + r)^4 absolute) also bounds the shortest chord: one
// whose exact f at its middle, -f'' (chord / 2)^2 / 2 with f'' ~ 8 R^2 at a grazed point, is
// within the rounding of 0 may be lost with its partner like a tangency. Measured against the
// exact reference (tests/validation_torus.cpp): chords down to ~1e-6 r are found for R / r = 40
// (~1e-4 r for R / r = 2560), shorter ones not: grazing depths c^2 / (8 r) of ~1e-13 r and ~1e-9 r
// (the 1e-3 mm chord of a 0.125 mm groove bottom grazed 1e-6 mm deep is found by a wide margin).
Roots torus(const Surface& s, const Vec3& o, const Vec3& d) {
    Roots r;
    const Roots bs = intersect_sphere(s.origin, s.radius + s.minor_radius, o, d);
    if (bs.count < 2) return r;
    const double dd = dot(d, d);
    const double tm = dot(s.origin - o, d) / dd;
    const Vec3 p = o + d * tm - s.origin;
    const double R2 = s.radius * s.radius, rr = s.minor_radius * s.minor_radius;
    const double pp = dot(p, p), pa = dot(p, s.axis), da = dot(d, s.axis);
    const double A = pp + (R2 - rr);
    const double c[5] = {A * A - 4.0 * R2 * (pp - pa * pa), 8.0 * R2 * pa * da,
                         2.0 * dd * A - 4.0 * R2 * (dd - da * da), 0.0, dd * dd};
    // The span is widened a little: a root on the bounding sphere itself (the outer equator of an
    // equatorial ray) must not sit on the interval's end, where its sign change would be lost.
    const double margin = 1e-6 * (s.radius + s.minor_radius);
    const PolyRoots roots = real_roots(c, 4, bs.t[0] - tm - margin, bs.t[1] - tm + margin);
    for (int i = 0; i < roots.count; ++i) r.push(roots.x[static_cast<size_t>(i)] + tm);
    return r;
}

}  // namespace

Roots intersect(const Surface& s, const Vec3& o, const Vec3& d) {
    Roots r;
    switch (s.kind) {
        case SurfaceKind::Plane: {
            const double dn = dot(d, s.axis);
            if (dn != 0) r.push(dot(s.origin - o, s.axis) / dn);
            return r;
        }
        case SurfaceKind::Sphere: return intersect_sphere(s.origin, s.radius, o, d);  // solve_quadratic orders them
        case SurfaceKind::Cylinder: return intersect_cylinder(s.origin, s.axis, s.radius, o, d);
        case SurfaceKind::Ellipsoid: return ellipsoid(s, o, d);
        case SurfaceKind::Cone: r = cone(s, o, d); break;
        case SurfaceKind::Torus: r = torus(s, o, d); break;
    }
    r.sort();
    return r;
}

double point_error_bound(const Surface& s, const Vec3& p) {
    return std::fabs(s.signed_distance(p)) + point_rounding_bound(s, p);
}

}  // namespace ltm
