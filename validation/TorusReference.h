#pragma once
// An INDEPENDENT reference for the intersections of a ray with a torus (the U-groove's bottom),
// in exact arithmetic: the tracer's torus code (trace/Intersect.cpp, trace/Polynomial.h) is
// checked against it. It shares nothing with trace/ or geometry/Surface.h: only the plain Vec3
// data type is used, and all of its arithmetic is done by MPFR (TorusReference.cpp derives it).
//
// The problem solved is the one the double inputs state exactly: the torus with centre C, axis
// direction a (not necessarily of unit length: the torus about the line C + s a), major radius R
// and minor radius r, and the line o + t d (d != 0, not necessarily unit). Every real t where the
// line meets the torus is found, with its multiplicity (1: the ray crosses the surface; 2: it is
// tangent to it; 3, 4: higher-order contact, e.g. 4 for a ray tangent to the top circle along
// that circle's direction), and each is rounded to the nearest double, with an enclosing
// interval. There is no error bound to carry: the coefficients are exact, the root isolation is
// exact (Sturm's theorem evaluated in exact dyadic arithmetic) and every root is refined until its
// rounding to double is decided.
//
// The quartic, its normalisation and the precision argument are in TorusReference.cpp.
#include <memory>
#include <vector>

#include "geometry/Vec3.h"

namespace ltm::validation {

struct TorusRoot {
    double t = 0;         // the exact root, rounded to the nearest double (ties: either neighbour)
    double lo = 0, hi = 0;  // doubles with lo <= root <= hi (lo = hi = t when t is the root exactly)
    int multiplicity = 1;   // 1 crossing, 2 tangency (touching: f keeps its sign), 3, 4 higher contact
    // Derivatives of f (below) at the root, rounded: the conditioning of the root. f'(t) is 0 for
    // a multiple root, f''(t) is 0 for multiplicity >= 3. Evaluated exactly at a dyadic point within
    // half an ulp of the root and rounded, so relative to the exact derivatives at the root they
    // are off by |f''| ulp / |f'| (resp. |f'''| ulp / |f''|) at most, plus one rounding.
    double slope = 0;      // f'(t)
    double curvature = 0;  // f''(t)
};

// f(t) = F(t) / |a|^2 with F the quartic of TorusReference.cpp: for a unit axis and a unit
// direction f is the textbook torus quartic
//     f(x) = (|x - C|^2 + R^2 - r^2)^2 - 4 R^2 (|x - C|^2 - ((x - C).a)^2)
// along x = o + t d (f < 0 inside the tube, > 0 outside).
class TorusReference {
public:
    // Throws std::invalid_argument for d = 0, a = 0, non-finite inputs, R <= 0 or r <= 0.
    TorusReference(const Vec3& centre, const Vec3& axis, double major, double minor, const Vec3& origin,
                   const Vec3& direction);
    ~TorusReference();
    TorusReference(const TorusReference&) = delete;
    TorusReference& operator=(const TorusReference&) = delete;

    // Every distinct real root, ascending (a tangency is one root of multiplicity 2).
    const std::vector<TorusRoot>& roots() const { return roots_; }

    // The k-th derivative (k = 0..4) of f at the double t, computed exactly and rounded to the
    // nearest double (its sign is exact: the test's "does f change sign here" is decided exactly).
    double f(double t, int k = 0) const;

    // Whether the k-th derivative of f (k = 0..3) has a real root in [a, b] (a <= b doubles),
    // decided exactly (Sturm's theorem): false proves f^(k) keeps one strict sign on [a, b] (for
    // k = 1: f is strictly monotone there).
    bool has_root_in(int k, double a, double b) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::vector<TorusRoot> roots_;
};

}  // namespace ltm::validation
