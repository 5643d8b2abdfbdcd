#include "geometry/Surface.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

namespace ltm {

const char* to_string(SurfaceKind kind) {
    switch (kind) {
        case SurfaceKind::Plane: return "plane";
        case SurfaceKind::Sphere: return "sphere";
        case SurfaceKind::Cylinder: return "cylinder";
        case SurfaceKind::Ellipsoid: return "ellipsoid";
        case SurfaceKind::Cone: return "cone";
        case SurfaceKind::Torus: return "torus";
    }
    return "?";
}

Mat3 rotation_from_euler_deg(const Vec3& a) {
    const double d = kPi / 180.0;
    const double cx = std::cos(a.x * d), sx = std::sin(a.x * d);
    const double cy = std::cos(a.y * d), sy = std::sin(a.y * d);
    const double cz = std::cos(a.z * d), sz = std::sin(a.z * d);
    Mat3 rx, ry, rz;
    rx.m = {1, 0, 0, 0, cx, -sx, 0, sx, cx};
    ry.m = {cy, 0, sy, 0, 1, 0, -sy, 0, cy};
    rz.m = {cz, -sz, 0, sz, cz, 0, 0, 0, 1};
    return rz * ry * rx;
}

Surface Surface::plane(const Vec3& point, const Vec3& normal) {
    Surface s;
    s.kind = SurfaceKind::Plane;
    s.origin = point;
    s.axis = normalize(normal);
    return s;
}
Surface Surface::sphere(const Vec3& centre, double radius) {
    Surface s;
    s.kind = SurfaceKind::Sphere;
    s.origin = centre;
    s.radius = radius;
    return s;
}
Surface Surface::cylinder(const Vec3& point_on_axis, const Vec3& axis, double radius) {
    Surface s;
    s.kind = SurfaceKind::Cylinder;
    s.origin = point_on_axis;
    s.axis = normalize(axis);
    s.radius = radius;
    return s;
}
Surface Surface::ellipsoid(const Vec3& centre, const Mat3& frame, const Vec3& semi_axes) {
    Surface s;
    s.kind = SurfaceKind::Ellipsoid;
    s.origin = centre;
    s.frame = frame;
    s.semi_axes = semi_axes;
    return s;
}
Surface Surface::cone(const Vec3& apex, const Vec3& axis, double half_angle) {
    Surface s;
    s.kind = SurfaceKind::Cone;
    s.origin = apex;
    s.axis = normalize(axis);
    s.angle = half_angle;
    return s;
}
Surface Surface::torus(const Vec3& centre, const Vec3& axis, double major, double minor) {
    Surface s;
    s.kind = SurfaceKind::Torus;
    s.origin = centre;
    s.axis = normalize(axis);
    s.radius = major;
    s.minor_radius = minor;
    return s;
}

namespace {

// Meridian-plane coordinates of p about an axis through o with unit direction u:
// h along the axis, q >= 0 the distance from the axis, e the unit radial direction.
struct Meridian {
    double h, q;
    Vec3 e;
};
Meridian meridian(const Vec3& p, const Vec3& o, const Vec3& u) {
    const Vec3 d = p - o;
    const double h = dot(d, u);
    const Vec3 r = d - u * h;
    const double q = length(r);
    Vec3 e;
    if (q > 0) {
        e = r / q;
    } else {
        Vec3 b2;
        orthonormal_basis(u, e, b2);
    }
    return {h, q, e};
}

// Closest point of the double cone (half-angle a) in the meridian half-plane (q >= 0): the two
// generator rays from the apex along (sin a, +-cos a).
void cone_closest(double q, double h, double a, double& cq, double& ch) {
    const double s = std::sin(a), c = std::cos(a);
    double best = INFINITY;
    for (double sign : {1.0, -1.0}) {
        const double dq = s, dh = sign * c;
        const double t = std::max(0.0, q * dq + h * dh);
        const double pq = t * dq, ph = t * dh;
        const double d2 = (q - pq) * (q - pq) + (h - ph) * (h - ph);
        if (d2 < best) {
            best = d2;
            cq = pq;
            ch = ph;
        }
    }
}

// The secular function of Eberly's method in the shifted variable u = t + e_k^2, with
// d_i = e_i^2 - e_k^2: the roots lie within ~e_k |y_k| of the pole at u = 0, and working in u keeps
// their full relative precision (in t they would drown in the rounding of e_k^2).
double secular(const Vec3& e, const Vec3& y, const Vec3& d, double u) {
    double f = -1.0;
    for (int i = 0; i < 3; ++i) {
        const double r = e[i] * y[i] / (u + d[i]);
        f += r * r;
    }
    return f;
}

Vec3 guarded(const Vec3& semi_axes, const Vec3& y) {
    const double emax = std::max({semi_axes.x, semi_axes.y, semi_axes.z});
    Vec3 g;
    for (int i = 0; i < 3; ++i) {
        const double floor_ = 1e-13 * emax;
        g[i] = std::fabs(y[i]) < floor_ ? std::copysign(floor_, y[i] == 0 ? 1.0 : y[i]) : y[i];
    }
    return g;
}

// Bisection to the last representable bit on a bracket where F changes sign.
double bisect(const Vec3& e, const Vec3& y, const Vec3& d, double lo, double hi, bool increasing) {
    for (int it = 0; it < 2200; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        const double f = secular(e, y, d, mid);
        if ((f > 0) == increasing) hi = mid; else lo = mid;
    }
    return 0.5 * (lo + hi);
}

// Solves for the closest (k = smallest axis, u > 0 side) or farthest (k = largest axis, u < 0
// side) stationary point.
Vec3 extreme_point(const Vec3& e, const Vec3& y_in, bool farthest) {
    const Vec3 y = guarded(e, y_in);
    int k = 0;
    for (int i = 1; i < 3; ++i)
        if (farthest ? e[i] > e[k] : e[i] < e[k]) k = i;
    Vec3 d;
    double ey = 0;
    for (int i = 0; i < 3; ++i) {
        d[i] = (e[i] - e[k]) * (e[i] + e[k]);
        ey += (e[i] * y[i]) * (e[i] * y[i]);
    }
    const double pole = e[k] * std::fabs(y[k]);
    double u;
    if (!farthest) {
        // F(pole) >= 0 (the k term alone is 1 there); F(sqrt(ey)) <= 0 (each |u + d_i| >= sqrt(ey)).
        u = bisect(e, y, d, pole, std::max(pole, std::sqrt(ey)), /*increasing=*/false);
    } else {
        // On u < 0 (t < -e_k^2) F rises from -1 to +inf: F(-sqrt(ey)) <= 0, F(-pole) >= 0.
        u = bisect(e, y, d, std::min(-pole, -std::sqrt(ey)), -pole, /*increasing=*/true);
    }
    Vec3 x;
    for (int i = 0; i < 3; ++i) x[i] = e[i] * e[i] * y[i] / (u + d[i]);
    return x;
}

}  // namespace

Vec3 ellipsoid_closest_point(const Vec3& e, const Vec3& y) { return extreme_point(e, y, false); }
Vec3 ellipsoid_farthest_point(const Vec3& e, const Vec3& y) { return extreme_point(e, y, true); }

double Surface::signed_distance(const Vec3& p) const {
    switch (kind) {
        case SurfaceKind::Plane: return dot(p - origin, axis);
        case SurfaceKind::Sphere: return distance(p, origin) - radius;
        case SurfaceKind::Cylinder: return meridian(p, origin, axis).q - radius;
        case SurfaceKind::Torus: {
            const Meridian m = meridian(p, origin, axis);
            return std::hypot(m.q - radius, m.h) - minor_radius;
        }
        case SurfaceKind::Cone: {
            const Meridian m = meridian(p, origin, axis);
            double cq = 0, ch = 0;
            cone_closest(m.q, m.h, angle, cq, ch);
            const double d = std::hypot(m.q - cq, m.h - ch);
            // Outside (away from the axis) is positive: compare with the cone's radius at height h.
            return m.q >= std::fabs(m.h) * std::tan(angle) ? d : -d;
        }
        case SurfaceKind::Ellipsoid: {
            const Vec3 y = frame.transposed() * (p - origin);
            const double f = (y.x / semi_axes.x) * (y.x / semi_axes.x) +
                             (y.y / semi_axes.y) * (y.y / semi_axes.y) +
                             (y.z / semi_axes.z) * (y.z / semi_axes.z);
            const double d = distance(y, ellipsoid_closest_point(semi_axes, y));
            return f >= 1.0 ? d : -d;
        }
    }
    return NAN;
}

Vec3 Surface::project(const Vec3& p) const {
    switch (kind) {
        case SurfaceKind::Plane: return p - axis * dot(p - origin, axis);
        case SurfaceKind::Sphere: {
            const Vec3 d = p - origin;
            const double l = length(d);
            return l > 0 ? origin + d * (radius / l) : origin + Vec3{0, 0, radius};
        }
        case SurfaceKind::Cylinder: {
            const Meridian m = meridian(p, origin, axis);
            return origin + axis * m.h + m.e * radius;
        }
        case SurfaceKind::Torus: {
            const Meridian m = meridian(p, origin, axis);
            const double dq = m.q - radius, dh = m.h;
            const double l = std::hypot(dq, dh);
            const double cq = l > 0 ? radius + dq * minor_radius / l : radius + minor_radius;
            const double ch = l > 0 ? dh * minor_radius / l : 0.0;
            return origin + axis * ch + m.e * cq;
        }
        case SurfaceKind::Cone: {
            const Meridian m = meridian(p, origin, axis);
            double cq = 0, ch = 0;
            cone_closest(m.q, m.h, angle, cq, ch);
            return origin + axis * ch + m.e * cq;
        }
        case SurfaceKind::Ellipsoid: {
            const Vec3 y = frame.transposed() * (p - origin);
            return origin + frame * ellipsoid_closest_point(semi_axes, y);
        }
    }
    return {NAN, NAN, NAN};
}

Vec3 Surface::normal(const Vec3& p) const {
    switch (kind) {
        case SurfaceKind::Plane: return axis;
        case SurfaceKind::Sphere: return normalize(p - origin);
        case SurfaceKind::Cylinder: return meridian(p, origin, axis).e;
        case SurfaceKind::Torus: {
            const Meridian m = meridian(p, origin, axis);
            return normalize(m.e * (m.q - radius) + axis * m.h);
        }
        case SurfaceKind::Cone: {
            const Meridian m = meridian(p, origin, axis);
            const double s = std::sin(angle), c = std::cos(angle);
            // Outward normal of the nappe on the side of p: (cos a, -+sin a) in (q, h).
            const double sh = m.h >= 0 ? 1.0 : -1.0;
            return normalize(m.e * c - axis * (sh * s));
        }
        case SurfaceKind::Ellipsoid: {
            const Vec3 y = frame.transposed() * (p - origin);
            const Vec3 g{y.x / (semi_axes.x * semi_axes.x), y.y / (semi_axes.y * semi_axes.y),
                         y.z / (semi_axes.z * semi_axes.z)};
            return normalize(frame * g);
        }
    }
    return {NAN, NAN, NAN};
}

std::string Surface::describe() const {
    switch (kind) {
        case SurfaceKind::Plane:
            return fmt::format("plane through ({:.9g}, {:.9g}, {:.9g}) normal ({:.9g}, {:.9g}, {:.9g})",
                               origin.x, origin.y, origin.z, axis.x, axis.y, axis.z);
        case SurfaceKind::Sphere:
            return fmt::format("sphere centre ({:.9g}, {:.9g}, {:.9g}) radius {:.9g}", origin.x,
                               origin.y, origin.z, radius);
        case SurfaceKind::Cylinder:
            return fmt::format("cylinder axis ({:.9g}, {:.9g}, {:.9g}) radius {:.9g}", axis.x, axis.y,
                               axis.z, radius);
        case SurfaceKind::Ellipsoid:
            return fmt::format("ellipsoid centre ({:.9g}, {:.9g}, {:.9g}) semi-axes {:.9g} {:.9g} {:.9g}",
                               origin.x, origin.y, origin.z, semi_axes.x, semi_axes.y, semi_axes.z);
        case SurfaceKind::Cone:
            return fmt::format("cone apex ({:.9g}, {:.9g}, {:.9g}) half-angle {:.9g} rad", origin.x,
                               origin.y, origin.z, angle);
        case SurfaceKind::Torus:
            return fmt::format("torus centre ({:.9g}, {:.9g}, {:.9g}) radii {:.9g} {:.9g}", origin.x,
                               origin.y, origin.z, radius, minor_radius);
    }
    return "?";
}

}  // namespace ltm
