#pragma once
// Closed-form ray paths in glass whose n^2 is quadratic (geometry/IndexField.h), and their first
// crossing of a quadric surface.
//
// The ray equation in the parameter tau (d tau = ds / n; p = n dr/ds, so |p| = n) is
//   dr/dtau = p,   dp/dtau = grad(n^2) / 2 = (b + H r) / 2,
// linear in r. In the eigenbasis of H (H = Q diag(h) Q^T, y = Q^T r, v = Q^T p, beta = Q^T b / 2,
// lambda = h / 2) it decouples into y_i'' = lambda_i y_i + beta_i, solved by
//   y_i(tau) = y_i(0) C_i(tau) + v_i(0) S_i(tau) + beta_i U_i(tau),
//   v_i(tau) = y_i(0) lambda_i S_i(tau) + v_i(0) C_i(tau) + beta_i S_i(tau),
// with C'' = lambda C, C(0) = 1, C'(0) = 0; S = integral of C; U = integral of S:
//   lambda < 0, w = sqrt(-lambda):  C = cos w tau,  S = sin(w tau) / w,  U = 2 sin^2(w tau / 2) / w^2;
//   lambda > 0, k = sqrt(lambda):   C = cosh k tau, S = sinh(k tau) / k, U = 2 sinh^2(k tau / 2) / k^2;
//   lambda = 0:                     C = 1,          S = tau,             U = tau^2 / 2.
// The half-angle forms of U do not cancel as w tau -> 0, so no series is needed. With H = 0 (a
// linear n^2) the path is the parabola r = r0 + p0 tau + b tau^2 / 4, evaluated in world
// coordinates directly. |p|^2 - n^2(r) is a constant of the motion (the Hamiltonian), 0 on a ray.
//
// First crossings. A quadric surface F(x) = |L (x - c)|^2 - R^2 (sphere, cylinder, ellipsoid) or
// F(x) = n . (x - o) (plane) along the path is f(tau) = F(r(tau)):
//  - on the parabola, a polynomial of degree 4 (2 for a plane): its roots are isolated exactly
//    (trace/Polynomial.h);
//  - where every eigen-direction the surface depends on has the same lambda < 0, a trigonometric
//    polynomial of degree 2 in theta = w tau (y = m + A cos theta + B sin theta there): with
//    t = tan(theta / 2), (1 + t^2)^2 f is a quartic in t, solved like the polynomial; the orbit is
//    periodic in theta, so one period holds every distinct root (the Luneburg sphere; a GRIN
//    rod's rim);
//  - where they share one lambda > 0, with z = e^(k tau), z^2 f is a quartic in z;
//  - otherwise (directions of different lambda mixed: a lens cap in a GRIN rod, a general
//    quadratic field) a bracketed root with a guarantee. On any interval where the path stays in the
//    glass, |f''| <= M (f'' = 2 |L p|^2 + 2 L (r - c) . L (b + H r) / 2, bounded with |p| <= n_max
//    and |r| <= the object's radius), so from tau0 with g = sign f > 0,
//      g(tau0 + h) >= g0 + g0' h - M h^2 / 2 > 0   for h < h_safe = 2 g0 / (sqrt(g0'^2 + 2 M g0) - g0'),
//    and no root is skipped by stepping h_safe. Where the upper bound g0 + g0' h + M h^2 / 2 turns
//    negative (g0' < 0, g0'^2 > 2 M g0), its first zero h_sure = 2 g0 / (-g0' + sqrt(g0'^2 - 2 M g0))
//    lies before the vertex -g0' / M, so g' <= g0' + M h < 0 on [0, h_sure]: exactly one, simple root
//    lies in [h_safe, h_sure], which Newton's method safeguarded by bisection polishes. This is
//    never a fixed-step scan: steps grow with the distance to the surface, and a grazing approach
//    (g0' -> 0) costs only logarithmically many steps in the closest approach.
#include <vector>

#include "geometry/IndexField.h"
#include "geometry/Surface.h"
#include "geometry/Vec3.h"
#include "trace/Patch.h"

namespace ltm {

// A quadratic n^2 field prepared for tracing: its eigenbasis and the bounds the root finder needs.
class GrinField {
public:
    // `n2_max` and `radius`: bounds of n^2 and of |x| over the glass (geometry/IndexField.h,
    // index_range; the object's bounding sphere).
    GrinField(const QuadraticForm& q, double n2_max, double radius);

    const QuadraticForm& form() const { return q_; }
    double n2(const Vec3& x) const { return q_(x); }
    bool parabolic() const { return parabolic_; }   // H = 0

    const Mat3& basis() const { return Q_; }         // columns: the eigenvectors of H
    const Vec3& lambda() const { return lambda_; }   // h / 2
    const Vec3& beta() const { return beta_; }       // Q^T b / 2
    double n2_max() const { return n2_max_; }
    double radius() const { return radius_; }
    double accel_max() const { return accel_max_; }  // a bound on |dp/dtau| = |b + H r| / 2 in the glass

private:
    QuadraticForm q_;
    Mat3 Q_;
    Vec3 lambda_, beta_;
    bool parabolic_ = false;
    double n2_max_ = 0, radius_ = 0, accel_max_ = 0;
};

// The path from (r0, p0) through a GrinField.
class GrinPath {
public:
    GrinPath(const GrinField& field, const Vec3& r0, const Vec3& p0);
    Vec3 position(double tau) const;
    Vec3 momentum(double tau) const;
    void state(double tau, Vec3& r, Vec3& p) const;
    // Arc length s = integral_0^tau |p| dtau (|p| = n, ds = n dtau), for Beer-Lambert: adaptive
    // Gauss-Legendre (|p| is smooth), to a relative accuracy of 1e-12.
    double arc_length(double tau) const;
    const Vec3& r0() const { return r0_; }
    const Vec3& p0() const { return p0_; }
    const Vec3& y0() const { return y0_; }  // r0 in the eigenbasis (r0 itself on a parabola)
    const Vec3& v0() const { return v0_; }  // p0 in the eigenbasis
    const GrinField& field() const { return *f_; }

private:
    const GrinField* f_;
    Vec3 r0_, p0_;
    Vec3 y0_, v0_;
};

// A quadric in the form the root finder uses: plane n . (x - o) = 0, or |L (x - c)|^2 = R^2.
struct Quadric {
    bool plane = false;
    Vec3 n, o;       // plane
    Mat3 L;          // |L (x - c)|^2 - R^2 (L = I: sphere; I - u u^T: cylinder; S^-1 F^T: ellipsoid)
    Vec3 c;
    double R2 = 0;
    double norm_L = 1;  // ||L||_2
    static Quadric from(const Surface& s);  // plane, sphere, cylinder, ellipsoid
    double value(const Vec3& x) const;
    double slope(const Vec3& x, const Vec3& p) const;  // dF/dtau = grad F . p
};

// A quadric as the paths of one field see it: which of the forms above its crossings take,
// prepared once per (field, surface).
class CurvedQuadric {
public:
    enum class Form { Polynomial, Trigonometric, Hyperbolic, General };
    CurvedQuadric(const GrinField& field, const Quadric& q);
    Form form() const { return form_; }
    const Quadric& quadric() const { return q_; }
    // The first root in (tmin, tmax) along the path (of this field) whose point lies on one of
    // the `count` patches of this surface (*which: its index; any point when count == 0), to
    // full precision, or +inf. `evaluations` (if given) counts the path evaluations.
    double first_crossing(const GrinPath& path, double tmin, double tmax, const Patch* patches, int count,
                          int* which = nullptr, long* evaluations = nullptr) const;

private:
    double general(const GrinPath& path, double tmin, double tmax, const Patch* patches, int count, int* which,
                   long* evals) const;
    const GrinField* f_;
    Quadric q_;
    Form form_ = Form::General;
    double lambda_ = 0;  // the common eigenvalue (/2) of the directions the surface depends on
    // The quadric in the eigenbasis: |G y - gc|^2 - R^2, or ne . y - no for a plane; only the
    // directions with seen_[i] enter (G's other columns, ne's other entries are exactly 0).
    Mat3 G_;
    Vec3 gc_, ne_;
    double no_ = 0;
    bool seen_[3] = {false, false, false};
};



}  // namespace ltm
