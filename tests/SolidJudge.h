#pragma once
// An independent inside/outside judge for the stress tests of the tracer (tests/trace_stress.cpp).
//
// Why it is independent: it is written here from the scene's parameters alone (the lens spec's
// radii, thickness and diameter; each defect's centre, semi-axes, frame, and a scratch's face,
// end points or arc, width, depth and profile), following the definitions in docs/scene-format.md
// and the conventions in geometry/Lens.h. It calls no containment code of the library: not
// Lens::contains / signed_distance, not ToolShape, ScratchPath, Surface or Tracer::medium_at, and
// it never looks at the mesh or the surface table. It only uses the Vec3/Mat3 arithmetic and the
// Scene structs (plain data). Where its formulation differs from the library's it does so on
// purpose: the caps are tested as "inside/outside the ball, or beyond the plane through the
// centre of curvature" instead of through the sag height field, the ends of a revolved scratch by
// the azimuth about the sweep's middle instead of the library's unwrapping, the distances to an
// ellipsoid by its Lipschitz bound.
//
// Where it is exact: every primitive (ball, half-space, cylinder, ellipsoid, the scratch's
// profile walls, floors and end planes) is classified by a signed function g whose value is a
// lower bound of the distance to that primitive's surface (the exact distance for balls, planes,
// the cylinder and the profile lines and circles in their meridian plane; |1 - rho| e_min for an
// ellipsoid; q sin(angle) for a half-plane through an axis), evaluated in double precision with
// an error of a few ulps of the scene's length scale L. A point with |g| <= band is "on" that
// primitive. The solid is the Boolean combination of the primitives (lens = front cap AND back
// cap AND rim cylinder; glass = lens AND NOT (union of the voids: bubbles, pits, scratches);
// particles inside), evaluated in three-valued (Kleene) logic: In AND On = On, Out AND On = Out,
// NOT On = On. So a point is classified as a definite medium only if it is farther than `band`
// from every surface that could decide its membership; a point within rounding distance of a
// surface (band = 1e-10 L, four orders of magnitude above the tracer's point error bound of
// 64 u L and the judge's own rounding) is "on the boundary", never a leak. Conversely, a tracer
// vertex that is not within the band of the boundary of the Boolean result (a hit on a part of
// a face that a pit removed, say) is judged to lie in a definite medium.
#include <algorithm>
#include <cmath>
#include <vector>

#include "geometry/Vec3.h"
#include "scene/Scene.h"

namespace ltm::test {

enum class Tri { Out = 0, On = 1, In = 2 };
inline Tri and3(Tri a, Tri b) { return static_cast<int>(a) < static_cast<int>(b) ? a : b; }
inline Tri or3(Tri a, Tri b) { return static_cast<int>(a) > static_cast<int>(b) ? a : b; }
inline Tri not3(Tri a) { return static_cast<Tri>(2 - static_cast<int>(a)); }
// g: a signed lower bound of the distance to a surface, positive on the member side.
inline Tri side(double g, double band) { return g > band ? Tri::In : (g < -band ? Tri::Out : Tri::On); }

enum class Where { Air, Glass, Absorber, Boundary };
inline const char* to_string(Where w) {
    switch (w) {
        case Where::Air: return "air";
        case Where::Glass: return "glass";
        case Where::Absorber: return "absorber";
        case Where::Boundary: return "boundary";
    }
    return "?";
}

class SolidJudge {
public:
    static constexpr double kRelativeBand = 1e-10;

    explicit SolidJudge(const Scene& scene) {
        const LensSpec& s = scene.object.lens;
        a_ = 0.5 * s.diameter;
        zf_ = -0.5 * s.center_thickness;
        zb_ = 0.5 * s.center_thickness;
        r1_ = s.r1;
        r2_ = s.r2;
        double L = std::max(a_, s.center_thickness);
        for (double R : {r1_, r2_})
            if (std::isfinite(R)) L = std::max(L, std::fabs(R));
        for (const Defect& d : scene.defects) {
            Prim p;
            p.particle = d.type == DefectType::Particle;
            if (d.type == DefectType::Scratch) {
                p.scratch = true;
                make_scratch(d, p);
            } else {
                p.c = d.center;
                p.inv = d.frame.transposed();
                p.e = d.semi_axes;
                p.sphere = d.is_sphere();
                p.e_min = std::min({p.e.x, p.e.y, p.e.z});
            }
            L = std::max(L, length(d.center));
            prims_.push_back(p);
        }
        scale_ = L;
        band_ = kRelativeBand * L;
    }

    double band() const { return band_; }
    double scale() const { return scale_; }

    Where at(const Vec3& p) const {
        Tri glass = lens(p);
        if (glass == Tri::Out) return Where::Air;  // every defect lies in or cuts the lens
        Tri absorber = Tri::Out;
        for (const Prim& q : prims_) {
            if (q.particle) {
                absorber = or3(absorber, ellipsoid(q, p));
                continue;
            }
            glass = and3(glass, not3(q.scratch ? scratch(q, p) : ellipsoid(q, p)));
        }
        // Particles lie strictly inside the glass: inside one is the absorber whatever else holds.
        if (absorber == Tri::In) return Where::Absorber;
        if (absorber == Tri::On) return Where::Boundary;
        return glass == Tri::In ? Where::Glass : glass == Tri::Out ? Where::Air : Where::Boundary;
    }

    // The signed distance-like value of the face (0 front, 1 back) alone: positive on the glass side.
    // Used to find seams (where a defect's wall meets the face) by bisection.
    double face_value(int side_, const Vec3& p) const {
        const double R = side_ == 0 ? r1_ : r2_;
        const double zv = side_ == 0 ? zf_ : zb_;
        const double glass_dir = side_ == 0 ? 1.0 : -1.0;
        if (std::isinf(R)) return glass_dir * (p.z - zv);
        const Vec3 C{0, 0, zv + R};
        const double dist = length(p - C) - std::fabs(R);
        return (R > 0) == (glass_dir > 0) ? -dist : dist;  // glass inside the ball (convex) or outside
    }
    // The point of face `side_` above (x, y): z = vertex + sag(R, rho) (geometry/Lens.h's equation).
    Vec3 face_point(int side_, double x, double y) const {
        const double R = side_ == 0 ? r1_ : r2_;
        const double zv = side_ == 0 ? zf_ : zb_;
        const double rho2 = x * x + y * y;
        const double sag = std::isinf(R) ? 0.0 : rho2 / (R * (1.0 + std::sqrt(std::max(0.0, 1.0 - rho2 / (R * R)))));
        return {x, y, zv + sag};
    }
    double aperture_radius() const { return a_; }
    double z_front_vertex() const { return zf_; }
    double z_back_vertex() const { return zb_; }
    double radius(int side_) const { return side_ == 0 ? r1_ : r2_; }

    // A scratch's profile point (s across, t depth into the glass) at fraction f along its path,
    // by the same parametrisation the judge classifies with (for aiming adversarial rays).
    Vec3 scratch_point(int defect, double f, double s, double t) const {
        const Prim& q = prims_.at(static_cast<size_t>(defect));
        if (!q.revolve) return q.o + q.u * (f * q.length) + q.s_axis * s + q.t_axis * t;
        const double phi = q.phi_mid + (f - 0.5) * q.sweep;
        const double qq = q.q0 + s * q.sq + t * q.tq, hh = q.h0 + s * q.sh + t * q.th;
        return q.o + q.u * hh + (q.e0 * std::cos(phi) + q.e1 * std::sin(phi)) * qq;
    }

private:
    struct Prim {
        bool scratch = false, particle = false;
        // Ellipsoid.
        Vec3 c, e;
        Mat3 inv;
        bool sphere = false;
        double e_min = 0;
        // Scratch: revolved about the axis (o, u) with azimuth frame e0, e1, the sweep centred at
        // phi_mid of width `sweep`; the path point (q0, h0) in meridian coordinates and the unit
        // profile axes S = (sq, sh) across, T = (tq, th) into the glass. Extruded: from o along u
        // for `length`, across s_axis, into the glass t_axis.
        bool revolve = true;
        Vec3 o, u, e0, e1, s_axis, t_axis;
        double phi_mid = 0, sweep = 0, length = 0;
        double q0 = 0, h0 = 0, sq = 0, sh = 0, tq = 0, th = 0;
        double w = 0, dep = 0, m = 0;
        bool vee = true;
    };

    // Front cap: glass at +z of it; back: at -z. A face whose centre of curvature lies on the glass
    // side (convex) bounds glass = inside its ball OR beyond the plane through the centre (z >= Cz
    // for the front); a concave one: outside the ball AND beyond that plane. For rho <= |R| this is
    // exactly "z beyond the face's sag" (the vertical line at rho meets the sphere once on each side
    // of the plane z = Cz; the face is the crossing on the vertex's side).
    Tri cap(const Vec3& p, double R, double zv, double glass_dir) const {
        if (std::isinf(R)) return side(glass_dir * (p.z - zv), band_);
        const double cz = zv + R;
        const double dist = length(p - Vec3{0, 0, cz}) - std::fabs(R);
        const Tri beyond = side(glass_dir * (p.z - cz), band_);
        if ((R > 0) == (glass_dir > 0)) return or3(beyond, side(-dist, band_));
        return and3(beyond, side(dist, band_));
    }
    Tri lens(const Vec3& p) const {
        const Tri rim = side(a_ - std::hypot(p.x, p.y), band_);
        if (rim == Tri::Out) return Tri::Out;
        return and3(rim, and3(cap(p, r1_, zf_, 1.0), cap(p, r2_, zb_, -1.0)));
    }
    Tri ellipsoid(const Prim& q, const Vec3& p) const {
        const Vec3 v = p - q.c;
        if (q.sphere) return side(q.e.x - length(v), band_);
        const Vec3 y = q.inv * v;
        const double rho = std::sqrt((y.x / q.e.x) * (y.x / q.e.x) + (y.y / q.e.y) * (y.y / q.e.y) +
                                     (y.z / q.e.z) * (y.z / q.e.z));
        // rho is Lipschitz with constant 1 / e_min, so (1 - rho) e_min bounds the distance.
        return side((1.0 - rho) * q.e_min, band_);
    }
    Tri scratch(const Prim& q, const Vec3& p) const {
        double s, t, g_ends;
        if (!q.revolve) {
            const Vec3 v = p - q.o;
            const double along = dot(v, q.u);
            s = dot(v, q.s_axis);
            t = dot(v, q.t_axis);
            g_ends = std::min(along, q.length - along);
        } else {
            const Vec3 v = p - q.o;
            const double h = dot(v, q.u);
            const Vec3 r = v - q.u * h;
            const double qq = length(r);
            double dphi = std::atan2(dot(r, q.e1), dot(r, q.e0)) - q.phi_mid;
            while (dphi > kPi) dphi -= 2 * kPi;
            while (dphi < -kPi) dphi += 2 * kPi;
            // Distance to the nearer end half-plane through the axis (q sin of the angle to it, or
            // q beyond a right angle).
            const double margin = 0.5 * q.sweep - std::fabs(dphi);
            g_ends = qq * std::sin(std::clamp(margin, -0.5 * kPi, 0.5 * kPi));
            const double dq = qq - q.q0, dh = h - q.h0;
            s = dq * q.sq + dh * q.sh;
            t = dq * q.tq + dh * q.th;
        }
        Tri in = and3(side(g_ends, band_), side(t + q.m, band_));
        if (in == Tri::Out) return in;
        const double w = q.w, dep = q.dep;
        if (q.vee) {
            // Below the two lines t = dep (1 -+ 2 s / w): signed distance to the nearer.
            const double k = 2.0 * dep / w;
            const double g = (dep - k * std::fabs(s) - t) / std::sqrt(1.0 + k * k);
            return and3(in, side(g, band_));
        }
        const double rb = dep <= 0.5 * w ? (0.25 * w * w + dep * dep) / (2.0 * dep) : 0.5 * w;
        const double tc = dep - rb;
        const Tri walls = side(0.5 * w - std::fabs(s), band_);
        const Tri bottom = or3(side(tc - t, band_), side(rb - std::hypot(s, t - tc), band_));
        return and3(in, and3(walls, bottom));
    }

    void make_scratch(const Defect& d, Prim& p) const {
        p.w = d.width;
        p.dep = d.depth;
        p.m = std::max(d.width, d.depth);
        p.vee = d.profile == ScratchProfile::V;
        const int face = d.side;
        const double R = face == 0 ? r1_ : r2_;
        const double glass_dir = face == 0 ? 1.0 : -1.0;  // +z into the glass for the front face
        const Vec3 C{0, 0, (face == 0 ? zf_ : zb_) + R};
        const bool convex = std::isfinite(R) && (R > 0) == (glass_dir > 0);  // glass inside the ball
        if (!d.arc) {
            const Vec3 a = face_point(face, d.start.x, d.start.y), b = face_point(face, d.end.x, d.end.y);
            if (std::isinf(R)) {
                p.revolve = false;
                p.o = a;
                p.length = length(b - a);
                p.u = (b - a) / p.length;
                p.t_axis = {0, 0, glass_dir};
                p.s_axis = normalize(cross(p.t_axis, p.u));
                return;
            }
            // The great circle through a and b about the normal of the plane (C, a, b); the profile
            // lies in the meridian plane: across = along the axis, depth = toward the glass radially.
            p.o = C;
            p.u = normalize(cross(a - C, b - C));
            p.e0 = normalize(a - C);
            p.e1 = cross(p.u, p.e0);
            const double phi_b = std::atan2(dot(b - C, p.e1), dot(b - C, p.e0));  // in (0, pi)
            p.phi_mid = 0.5 * phi_b;
            p.sweep = phi_b;
            p.q0 = std::fabs(R);
            p.h0 = 0;
            p.sq = 0;
            p.sh = 1;
            p.tq = convex ? -1.0 : 1.0;
            p.th = 0;
            return;
        }
        // An arc: the points of the face at 3D distance r from the centre point, swept by azimuth
        // right-handed about +z: about the axis w (the face's normal, or the direction from the
        // centre of curvature to the centre point), taken with w.z >= 0, from the projection of +x.
        const Vec3 cp = face_point(face, d.arc_center.x, d.arc_center.y);
        Vec3 axis;
        if (std::isinf(R)) {
            p.o = cp;
            p.u = {0, 0, -glass_dir};  // the face's outward normal
            p.q0 = d.arc_radius;
            p.h0 = 0;
            p.sq = 1;
            p.sh = 0;
            p.tq = 0;
            p.th = -1;
            axis = p.u;
        } else {
            const double Ra = std::fabs(R);
            p.o = C;
            p.u = normalize(cp - C);
            const double alpha = 2.0 * std::asin(d.arc_radius / (2.0 * Ra));
            p.q0 = Ra * std::sin(alpha);
            p.h0 = Ra * std::cos(alpha);
            const double into = convex ? -1.0 : 1.0;  // depth against (or along) the outward radial
            p.tq = into * std::sin(alpha);
            p.th = into * std::cos(alpha);
            p.sq = std::cos(alpha);
            p.sh = -std::sin(alpha);
            axis = p.u;
        }
        const Vec3 wz = axis.z < 0 ? -axis : axis;
        Vec3 e0 = Vec3{1, 0, 0} - wz * wz.x;
        if (length(e0) < 1e-6) e0 = Vec3{0, 1, 0} - wz * wz.y;
        e0 = normalize(e0);
        // The frame about p.u; angles about wz are the user's.
        const double mirror = axis.z < 0 ? -1.0 : 1.0;
        p.e0 = e0;
        p.e1 = cross(p.u, e0);
        const double a0 = mirror * d.start_angle * kPi / 180.0, a1 = mirror * d.end_angle * kPi / 180.0;
        p.phi_mid = 0.5 * (a0 + a1);
        p.sweep = std::fabs(a1 - a0);
    }

    double a_ = 0, zf_ = 0, zb_ = 0, r1_ = INFINITY, r2_ = INFINITY;
    double scale_ = 1, band_ = 0;
    std::vector<Prim> prims_;
};

}  // namespace ltm::test
