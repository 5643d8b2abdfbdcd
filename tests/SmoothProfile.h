// A smooth radial index profile and a rigorous bound on the Hessian of its n^2, for the tests and
// the benchmark of tetrahedral meshing (tests/geometry_tetmesh.cpp, bench/bench_tetgen.cpp). The
// defects layer will own the field itself; this copy only serves to drive and check the mesher.
//
//   n(x) = n0 + dn q,   q = (1 - s)^2,   s = |x|^2 / a^2
// (n0 at the surface |x| = a, n0 + dn at the centre, flat at both.)
//
// Hessian of n^2 = n0^2 + 2 n0 dn q + dn^2 q^2:
//   D^2 n^2 = 2 dn (n0 + dn q) D^2 q + 2 dn^2 grad q grad q^T, so
//   ||D^2 n^2||_2 <= 2 |dn| |n0 + dn q| ||D^2 q||_2 + 2 dn^2 |grad q|^2.
// With grad s = 2 x / a^2 and D^2 s = 2 I / a^2:
//   grad q = -4 (1 - s) x / a^2,             |grad q|^2 = 16 s (1 - s)^2 / a^2;
//   D^2 q = 8 x x^T / a^4 - 4 (1 - s) I / a^2, eigenvalues (12 s - 4) / a^2 along x and
//           (4 s - 4) / a^2 (twice) across, so ||D^2 q||_2 = max(|12 s - 4|, |4 s - 4|) / a^2.
// Over a ball B(c, r) the radius |x| ranges over [max(0, |c| - r), |c| + r], so s over
// [s0, s1]; each factor is bounded by its own maximum over that interval:
//   ||D^2 q||: the larger of two absolute values of linear functions of s, so its maximum is at
//     an end: max(|12 s0 - 4|, |12 s1 - 4|, |4 s0 - 4|, |4 s1 - 4|) / a^2;
//   q = (1 - s)^2 ranges over [q_lo, q_hi] with q_hi at an end and q_lo = 0 if 1 is in [s0, s1],
//     else at an end; n0 + dn q is linear in q, so |n0 + dn q| is largest at q_lo or q_hi;
//   g(s) = s (1 - s)^2 has g' = (1 - s)(1 - 3 s): a maximum 4/27 at s = 1/3, a minimum 0 at
//     s = 1, so max g over [s0, s1] is at an end or, if 1/3 is inside, 4/27.
// The bound holds everywhere (also outside |x| <= a). Over the whole ball |x| <= a (s in [0, 1])
// it is 16 |dn| (|n0| + |dn|) / a^2 + 128 dn^2 / (27 a^2). The double evaluation rounds it by a
// few ulps, far below any meaning it has.
#pragma once

#include <algorithm>
#include <cmath>

#include "geometry/Vec3.h"

namespace ltm::test {

struct SmoothProfile {
    double n0 = 1.5, dn = 0.02, a = 1.0;

    double n(const Vec3& x) const {
        const double s = length2(x) / (a * a);
        return n0 + dn * (1 - s) * (1 - s);
    }
    double n2(const Vec3& x) const {
        const double v = n(x);
        return v * v;
    }
    // An upper bound on ||D^2 n^2||_2 over the ball (c, r) (see above).
    double hessian_bound(const Vec3& c, double r) const {
        const double rho = length(c), lo = std::max(0.0, rho - r), hi = rho + r;
        const double s0 = lo * lo / (a * a), s1 = hi * hi / (a * a);
        const double d2q = std::max({std::fabs(12 * s0 - 4), std::fabs(12 * s1 - 4), std::fabs(4 * s0 - 4),
                                     std::fabs(4 * s1 - 4)}) /
                           (a * a);
        const double q0 = (1 - s0) * (1 - s0), q1 = (1 - s1) * (1 - s1);
        const double q_hi = std::max(q0, q1), q_lo = (s0 <= 1 && 1 <= s1) ? 0.0 : std::min(q0, q1);
        const double n_max = std::max(std::fabs(n0 + dn * q_lo), std::fabs(n0 + dn * q_hi));
        auto g = [](double s) { return s * (1 - s) * (1 - s); };
        double g_max = std::max(g(s0), g(s1));
        if (s0 <= 1.0 / 3 && 1.0 / 3 <= s1) g_max = std::max(g_max, 4.0 / 27);
        return 2 * std::fabs(dn) * n_max * d2q + 2 * dn * dn * 16 * g_max / (a * a);
    }
    // The bound over the whole ball |x| <= a.
    double global_hessian_bound() const {
        return 16 * std::fabs(dn) * (std::fabs(n0) + std::fabs(dn)) / (a * a) + 128 * dn * dn / (27 * a * a);
    }
};

}  // namespace ltm::test
