#include "defects/ScratchPath.h"

#include <cmath>

namespace ltm {

Vec3 ScratchPath::place(double f, const Point2& p) const {
    if (!revolve) return p0 + dir * (f * length) + s_axis * p.s + t_axis * p.t;
    const double phi = phi0 + f * (phi1 - phi0);
    const double q = q0 + p.s * sq + p.t * tq;
    const double h = h0 + p.s * sh + p.t * th;
    return o + u * h + (e0 * std::cos(phi) + e1 * std::sin(phi)) * q;
}

double ScratchPath::path_length() const { return revolve ? std::fabs(phi1 - phi0) * q0 : length; }

Surface ScratchPath::line_surface(const Point2& a, const Point2& b) const {
    if (!revolve) {
        const Vec3 pa = place(0, a), pb = place(0, b);
        return Surface::plane(pa, cross(pb - pa, dir));
    }
    const double qa = q0 + a.s * sq + a.t * tq, ha = h0 + a.s * sh + a.t * th;
    const double qb = q0 + b.s * sq + b.t * tq, hb = h0 + b.s * sh + b.t * th;
    const double dq = qb - qa, dh = hb - ha;
    const double scale = std::hypot(dq, dh);
    if (std::fabs(dh) <= 1e-12 * scale) return Surface::plane(o + u * ha, u);        // annulus
    if (std::fabs(dq) <= 1e-12 * scale) return Surface::cylinder(o, u, qa);         // coaxial tube
    // The line meets the axis (q = 0) at h = ha - qa dh / dq: the cone's apex.
    const double h_apex = ha - qa * dh / dq;
    return Surface::cone(o + u * h_apex, u, std::atan2(std::fabs(dq), std::fabs(dh)));
}

Surface ScratchPath::circle_surface(const Point2& c, double r) const {
    if (!revolve) return Surface::cylinder(place(0, c), dir, r);
    const double qc = q0 + c.s * sq + c.t * tq, hc = h0 + c.s * sh + c.t * th;
    if (std::fabs(qc) <= 1e-12 * r) return Surface::sphere(o + u * hc, r);
    return Surface::torus(o + u * hc, u, qc, r);
}

Surface ScratchPath::end_surface(int which) const {
    if (!revolve) return Surface::plane(p0 + dir * (which ? length : 0.0), which ? dir : -dir);
    const double phi = which ? phi1 : phi0;
    const Vec3 tangent = e1 * std::cos(phi) - e0 * std::sin(phi);
    return Surface::plane(o, which ? tangent : -tangent);
}

ScratchPath scratch_path(const Lens& lens, const Defect& d) {
    ScratchPath p;
    const double R = d.side == 0 ? lens.spec().r1 : lens.spec().r2;
    const Surface face = d.side == 0 ? lens.front_surface() : lens.back_surface();
    const double sign = d.side == 0 ? lens.front_normal_sign() : lens.back_normal_sign();
    // Azimuths are given right-handed about +z from +x; with the axis pointing to -z the sweep
    // angle is mirrored so the user's angles keep their meaning.
    auto azimuth_frame = [&](const Vec3& axis) {
        p.u = axis;
        Vec3 x{1, 0, 0};
        Vec3 e0 = x - axis * dot(axis, x);
        if (length(e0) < 1e-6) e0 = Vec3{0, 1, 0} - axis * axis.y;
        p.e0 = normalize(e0);
        p.e1 = cross(p.u, p.e0);
        const double mirror = axis.z < 0 ? -1.0 : 1.0;
        p.phi0 = mirror * d.start_angle * kPi / 180.0;
        p.phi1 = mirror * d.end_angle * kPi / 180.0;
    };
    if (!d.arc) {
        const Vec3 a = lens.surface_point(d.side, d.start.x, d.start.y);
        const Vec3 b = lens.surface_point(d.side, d.end.x, d.end.y);
        if (std::isinf(R)) {
            p.revolve = false;
            p.p0 = a;
            p.length = distance(a, b);
            p.dir = (b - a) / p.length;
            p.t_axis = -lens.surface_outward_normal(d.side, a.x, a.y);
            p.s_axis = normalize(cross(p.t_axis, p.dir));
            return p;
        }
        // Great circle through a and b: axis normal to the plane (C, a, b).
        const Vec3 c = face.origin;
        p.o = c;
        p.u = normalize(cross(a - c, b - c));
        p.e0 = normalize(a - c);
        p.e1 = cross(p.u, p.e0);
        p.phi0 = 0;
        p.phi1 = std::atan2(dot(b - c, p.e1), dot(b - c, p.e0));
        p.q0 = std::fabs(R);
        p.h0 = 0;
        // The outward glass normal is sign * (radial), i.e. (sign, 0) in (q, h); depth goes against it.
        p.tq = -sign;
        p.th = 0;
        p.sq = 0;
        p.sh = 1;
        return p;
    }
    const Vec3 centre = lens.surface_point(d.side, d.arc_center.x, d.arc_center.y);
    if (std::isinf(R)) {
        p.o = centre;
        azimuth_frame(lens.surface_outward_normal(d.side, centre.x, centre.y));
        p.q0 = d.arc_radius;
        p.h0 = 0;
        p.sq = 1;
        p.sh = 0;
        p.tq = 0;
        p.th = -1;
        return p;
    }
    // Small circle at chord distance r from the centre point: polar angle alpha = 2 asin(r / 2R)
    // from the axis through the sphere's centre C and the centre point.
    const Vec3 c = face.origin;
    const double Ra = std::fabs(R);
    p.o = c;
    azimuth_frame(normalize(centre - c));
    const double alpha = 2.0 * std::asin(d.arc_radius / (2.0 * Ra));
    p.q0 = Ra * std::sin(alpha);
    p.h0 = Ra * std::cos(alpha);
    // In (q, h): the sphere's outward normal is (sin a, cos a); the tangent across the path is
    // (cos a, -sin a).
    p.tq = -sign * std::sin(alpha);
    p.th = -sign * std::cos(alpha);
    p.sq = std::cos(alpha);
    p.sh = -std::sin(alpha);
    return p;
}

}  // namespace ltm
