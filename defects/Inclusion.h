#pragma once
// The index of refraction of an inhomogeneity defect (docs/conventions.md, "Index inhomogeneities"):
// inside the ellipsoid with centre c, body axes the columns of F and semi-axes e, with the
// body-frame ellipsoidal radius rho (rho^2 = s = sum_i ((F^T (x - c))_i / e_i)^2),
//   smooth:  n = n_glass + delta_n (1 - s)^2  for s < 1, n_glass outside (n and grad n continuous);
//   uniform: n = n_glass + delta_n            for s < 1 (a sharp interface on the ellipsoid).
#include "defects/Defect.h"
#include "geometry/Vec3.h"

namespace ltm {

class InclusionField {
public:
    // Precondition: d is an inhomogeneity; n_glass is the homogeneous glass's index around it.
    InclusionField(const Defect& d, double n_glass);

    double s(const Vec3& x) const;  // rho^2
    double n(const Vec3& x) const;
    double n2(const Vec3& x) const { const double v = n(x); return v * v; }
    bool inside(const Vec3& x) const { return s(x) < 1.0; }

    // An upper bound on ||D^2 n^2||_2 over the ball (centre, radius), for the smooth profile (the
    // uniform one is constant inside: 0). With q = (1 - s)^2, n^2 = (n0 + dn q)^2 and
    //   D^2 n^2 = 2 dn (n0 + dn q) D^2 q + 2 dn^2 grad q grad q^T,
    //   grad q = -2 (1 - s) grad s,   D^2 q = 2 grad s grad s^T - 2 (1 - s) D^2 s,
    //   grad s = 2 F S y,  D^2 s = 2 F S F^T  (y = F^T (x - c), S = diag(1 / e_i^2)),
    // so with e_min the smallest semi-axis: |grad s|^2 = 4 |S y|^2 <= 4 s / e_min^2 and
    // ||D^2 s|| = 2 / e_min^2, hence for s <= 1
    //   ||D^2 q|| <= 8 s / e_min^2 + 4 (1 - s) / e_min^2 = 4 (1 + s) / e_min^2,
    //   |grad q|^2 <= 16 s (1 - s)^2 / e_min^2,
    // and q, D^2 q vanish for s >= 1. Over the ball, sqrt(s) lies within radius / e_min of its
    // value at the centre (the map x -> S^1/2 F^T (x - c) is 1/e_min-Lipschitz), which bounds s,
    // q and s (1 - s)^2 there.
    double hessian_bound(const Vec3& centre, double radius) const;

    // The smooth profile's polynomial continued beyond the ellipsoid: n = n_glass + delta_n (1 - s)^2
    // for s < s_ext (C-infinity across s = 1), n_glass beyond. What a tetrahedral mesh
    // interpolates (SolidBuilder.cpp, index_region): paths use the mesh only inside (s < 1), but
    // the tetrahedra that straddle the ellipsoid interpolate vertices outside it, and the field's
    // own kink there (D^2 n jumps from 8 delta_n / e^2 to 0) would bias them.
    double extended_n2(const Vec3& x, double s_ext) const;
    // Laplacian of extended_n2 (for s < s_ext; 0 beyond). With q = (1 - s)^2,
    //   lap n^2 = 2 dn (n0 + dn q) lap q + 2 dn^2 |grad q|^2,
    //   lap q = 2 |grad s|^2 - 2 (1 - s) lap s,  |grad s|^2 = 4 |S y|^2,  lap s = 2 tr S.
    double extended_laplacian_n2(const Vec3& x, double s_ext) const;
    // Hessian of extended_n2 (for s < s_ext; 0 beyond), as above:
    //   D^2 n^2 = 2 dn (n0 + dn q) D^2 q + 2 dn^2 grad q grad q^T, grad s = 2 F S y, D^2 s = 2 F S F^T.
    Mat3 extended_hessian_n2(const Vec3& x, double s_ext) const;
    // The bound of the tetrahedral criterion (geometry/TetMesh.h: M r^2 / 2 <= tolerance) for a
    // mesh of extended_n2 (s_ext > 1) over the ball (centre, radius): 0 when the ball lies outside
    // the ellipsoid (no path uses the mesh there); with s_ext <= 1, hessian_bound. Otherwise the
    // polynomial's Hessian bound over the whole ball (as hessian_bound, with, for s > 1,
    // ||D^2 q|| <= 8 s / e_min^2 + 4 (s - 1) / e_min^2 = (12 s - 4) / e_min^2 and q, s (1 - s)^2
    // increasing), and where the ball reaches beyond s_ext, where the mesh holds n_glass^2
    // instead of the polynomial, 2 J / radius^2 more: the interpolant of that difference is at
    // most J = max |(n0 + dn q)^2 - n0^2| <= 2 n0 |dn| q + dn^2 q^2 there (q at the ball's
    // largest s), which M r^2 / 2 then covers.
    double extended_hessian_bound(const Vec3& centre, double radius, double s_ext) const;

    const Vec3& center() const { return c_; }
    double max_semi_axis() const;
    double min_semi_axis() const;

private:
    // The bound of hessian_bound's formula over s in [s_lo, s_hi] (s_hi may exceed 1: the
    // polynomial continued, extended_hessian_bound).
    double curvature_bound(double s_lo, double s_hi) const;

    Vec3 c_, e_;
    Vec3 inv_e2_;  // 1 / e_i^2
    Mat3 ft_;  // F^T
    double n0_, dn_;
    bool smooth_;
};

}  // namespace ltm
