#pragma once
// Real roots of polynomials of degree <= 4 in an interval, isolated with a guarantee.
//
// Method (the critical-point recursion; e.g. C. Yuksel, "High-Performance Polynomial Root
// Finding for Graphics", Proc. ACM CGIT 5(3), 2022): the roots of p' split [lo, hi] into intervals
// on which p is monotone; each holds at most one root of p, and exactly one iff p changes sign
// over it. The critical points come from the same procedure applied to p' (down to the quadratic,
// solved in closed form with the stable formula). Each sign-changing interval is narrowed by
// Newton steps safeguarded by bisection, so the root is bracketed at every step and found to the
// last bit the evaluation allows (|p(x)| ~ the rounding of evaluating p). A root of even
// multiplicity (p touches 0 without crossing) is not a crossing and is not reported, which is
// what a ray that grazes a surface needs: no spurious hit.
#include <array>
#include <cstddef>

namespace ltm {

struct PolyRoots {
    int count = 0;
    std::array<double, 4> x{};
    void push(double v) {
        if (count < 4) x[static_cast<std::size_t>(count++)] = v;
    }
};

// The roots in [lo, hi] of sum_i c[i] x^i (degree <= 4, c has degree + 1 entries), ascending.
// Leading coefficients that are exactly 0 lower the degree.
PolyRoots real_roots(const double* c, int degree, double lo, double hi);

// Horner evaluation of the polynomial and of its derivative.
double poly_eval(const double* c, int degree, double x);
double poly_derivative(const double* c, int degree, double x);

}  // namespace ltm
