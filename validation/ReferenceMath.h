#pragma once
// The small pieces of closed-form geometry both reference solvers of validation/ use
// (AnalyticScene.h, GrinReference.h), written once. Independent of trace/ and geometry/ like them.
#include <algorithm>
#include <cmath>
#include <string>

namespace ltm::validation {

// "defects[k]": how scene files and messages name the k-th defect.
inline std::string defect_key(int k) { return "defects[" + std::to_string(k) + "]"; }

// sag(R, rho) = R - sgn(R) sqrt(R^2 - rho^2): the height of a sphere of signed radius R above its
// vertex tangent plane at radial distance rho (the vertex at the origin, centre at (0, 0, R)).
// Derivation: the sphere through the vertex with centre (0, 0, R) is rho^2 + (z - R)^2 = R^2;
// the branch through the vertex (z = 0 at rho = 0) is z - R = -sgn(R) sqrt(R^2 - rho^2).
// Evaluated without cancellation for small rho by multiplying with the conjugate:
//   R - sgn(R) s = (R^2 - s^2) / (R + sgn(R) s) = rho^2 / (R + sgn(R) s),  s = sqrt(R^2 - rho^2),
// and s = sqrt((|R| - rho)(|R| + rho)) (no cancellation in R^2 - rho^2 near rho = |R|). 0 for a
// plane (R = inf).
inline double sag(double R, double rho) {
    if (!std::isfinite(R)) return 0.0;
    const double aR = std::fabs(R);
    const double s = std::sqrt(std::max(0.0, (aR - rho) * (aR + rho)));
    return rho * rho / (R + std::copysign(s, R));
}

// Roots of A t^2 + 2 b t + C = 0 (A > 0) given its reduced discriminant disc = b^2 - A C, which
// the caller computes in a form free of cancellation. The textbook formula (-b +- sqrt(disc)) / A
// loses all digits of the smaller root when b^2 >> |A C| (subtracting nearly equal numbers).
// The stable form (Press et al., Numerical Recipes, 3rd ed., Sec. 5.6) never subtracts:
//   q = -(b + sgn(b) sqrt(disc))   (two terms of the same sign),
//   t1 = q / A                     (the root of larger magnitude),
//   t2 = C / q                     (Vieta: t1 t2 = C / A).
// Returns false if there is no real root; otherwise lo <= hi.
inline bool stable_roots(double A, double b, double C, double disc, double& lo, double& hi) {
    if (!(disc >= 0.0) || !(A > 0.0)) return false;
    const double q = -(b + std::copysign(std::sqrt(disc), b));
    if (q == 0.0) {  // b = 0 and disc = 0: the double root t = 0
        lo = hi = 0.0;
        return true;
    }
    const double t1 = q / A, t2 = C / q;
    lo = std::min(t1, t2);
    hi = std::max(t1, t2);
    return true;
}

}  // namespace ltm::validation
