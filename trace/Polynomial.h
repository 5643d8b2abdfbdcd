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
#include <cmath>
#include <cstddef>
#include <limits>

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

// The root in [a, b] of a function f monotone there, with f(x0) and f'(x0) known at x0 (a or b)
// and f(a) of sign opposite to f(b): Newton's method safeguarded by bisection (Press et al.,
// Numerical Recipes, 3rd ed., Sec. 9.4, rtsafe). A Newton step that would leave the bracket, or
// that does not shrink to less than half the step before, is replaced by bisection, and the
// bracket is kept around the root. Stops when the step is below 2 ulps of the root (or below the
// smallest normal double near 0) or f is exactly 0. `eval(x, f, df)` evaluates both at x.
template <class Eval>
double safeguarded_newton(const Eval& eval, double a, double b, double fa, double x0, double f0, double df0) {
    double x = x0, f = f0, df = df0;
    double dx_old = b - a, dx = dx_old;
    for (int it = 0; it < 200; ++it) {
        if (f == 0) return x;
        if (((x - b) * df - f) * ((x - a) * df - f) > 0 || std::fabs(2.0 * f) > std::fabs(dx_old * df)) {
            dx_old = dx;
            dx = 0.5 * (b - a);
            x = a + dx;
        } else {
            dx_old = dx;
            dx = f / df;
            x -= dx;
        }
        if (std::fabs(dx) <= 2.0 * std::numeric_limits<double>::epsilon() * std::fabs(x) ||
            std::fabs(dx) < std::numeric_limits<double>::min())
            return x;
        eval(x, f, df);
        if ((f < 0) == (fa < 0)) a = x; else b = x;
    }
    return x;
}

// Horner evaluation of the polynomial and of its derivative.
double poly_eval(const double* c, int degree, double x);
double poly_derivative(const double* c, int degree, double x);

}  // namespace ltm
