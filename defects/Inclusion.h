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
    // An upper bound on ||D^2 extended_n2||_2 over the ball, valid while the ball stays within
    // s < s_ext (0 when it lies outside the ellipsoid: no path uses it there). As hessian_bound,
    // with, for s > 1, ||D^2 q|| <= 8 s / e_min^2 + 4 (s - 1) / e_min^2 = (12 s - 4) / e_min^2
    // and q, s (1 - s)^2 increasing in s.
    double extended_hessian_bound(const Vec3& centre, double radius) const;
    // A lower bound on what hessian_bound and extended_hessian_bound return for any ball that
    // reaches s >= 1 from inside: there ||D^2 q|| is bounded by 8 / e_min^2 or more and the factor
    // n0 + |dn| q_max by n0 or more, so 16 |dn| n0 / e_min^2.
    double straddling_hessian_floor() const;

    const Vec3& center() const { return c_; }
    double max_semi_axis() const;
    double min_semi_axis() const;

private:
    Vec3 c_, e_;
    Vec3 inv_e2_;  // 1 / e_i^2
    Mat3 ft_;  // F^T
    double n0_, dn_;
    bool smooth_;
};

}  // namespace ltm
