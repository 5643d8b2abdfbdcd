#include "trace/Polynomial.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ltm {

double poly_eval(const double* c, int degree, double x) {
    double v = c[degree];
    for (int i = degree - 1; i >= 0; --i) v = v * x + c[i];
    return v;
}

double poly_derivative(const double* c, int degree, double x) {
    double v = 0;
    for (int i = degree; i >= 1; --i) v = v * x + i * c[i];
    return v;
}

namespace {

// The root of p in [a, b], given p(a) and p(b) of opposite signs and p monotone on [a, b]:
// safeguarded Newton (Polynomial.h) from the end with the smaller |p|. A bracket much wider than
// the magnitude of its finite end (the outer intervals reach the Cauchy bound) is first narrowed
// by doubling steps out from that end.
double solve_monotone(const double* c, int degree, double a, double b, double pa, double pb) {
    auto narrow = [&](double x, double px) {
        if ((px < 0) == (pa < 0)) {
            a = x;
            pa = px;
        } else {
            b = x;
            pb = px;
        }
    };
    const double near = std::min(std::fabs(a), std::fabs(b));
    if (b - a > 64.0 * std::max(1.0, near)) {
        const bool from_a = std::fabs(a) <= std::fabs(b);
        for (double step = std::max(1.0, near); b - a > 4.0 * step; step *= 2.0) {
            const double x = from_a ? a + step : b - step;
            const double px = poly_eval(c, degree, x);
            if (px == 0) return x;
            const bool crossed = (px < 0) != (pa < 0);
            narrow(x, px);
            if (crossed == from_a) break;  // the root lies between the end and x
        }
    }
    const double x = std::fabs(pa) <= std::fabs(pb) ? a : b;
    return safeguarded_newton(
        [&](double t, double& f, double& df) {
            f = poly_eval(c, degree, t);
            df = poly_derivative(c, degree, t);
        },
        a, b, pa, x, x == a ? pa : pb, poly_derivative(c, degree, x));
}

// Roots of the quadratic c0 + c1 x + c2 x^2 (c2 != 0) in [lo, hi], ascending; a double root
// (zero discriminant) touches without crossing and is skipped.
PolyRoots quadratic_roots(const double* c, double lo, double hi) {
    PolyRoots r;
    const double a = c[2], b = c[1], cc = c[0];
    const double disc = b * b - 4.0 * a * cc;
    if (!(disc > 0)) return r;
    const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
    double x0 = q / a, x1 = q != 0 ? cc / q : x0;
    if (x0 > x1) std::swap(x0, x1);
    if (x0 >= lo && x0 <= hi) r.push(x0);
    if (x1 >= lo && x1 <= hi && x1 != x0) r.push(x1);
    return r;
}

}  // namespace

PolyRoots real_roots(const double* c, int degree, double lo, double hi) {
    while (degree > 0 && c[degree] == 0) --degree;
    PolyRoots r;
    if (degree <= 0 || !(lo <= hi)) return r;
    if (degree == 1) {
        const double x = -c[0] / c[1];
        if (x >= lo && x <= hi) r.push(x);
        return r;
    }
    if (degree == 2) return quadratic_roots(c, lo, hi);
    // Critical points: the roots of p' in (lo, hi).
    double d[4];
    for (int i = 1; i <= degree; ++i) d[i - 1] = i * c[i];
    const PolyRoots crit = real_roots(d, degree - 1, lo, hi);
    double ends[6];
    int n = 0;
    ends[n++] = lo;
    for (int i = 0; i < crit.count; ++i)
        if (crit.x[static_cast<size_t>(i)] > ends[n - 1] && crit.x[static_cast<size_t>(i)] < hi) ends[n++] = crit.x[static_cast<size_t>(i)];
    ends[n++] = hi;
    double pa = poly_eval(c, degree, ends[0]);
    if (pa == 0) r.push(ends[0]);
    for (int i = 0; i + 1 < n; ++i) {
        const double b = ends[i + 1];
        const double pb = poly_eval(c, degree, b);
        if (pb == 0) {
            // An exact zero at a critical point is a double root (no crossing) unless the sign
            // differs on both sides; at the interval's end it is a root of the interval.
            if (i + 2 == n || (pa < 0) != (poly_eval(c, degree, ends[i + 2]) < 0)) r.push(b);
        } else if (pa != 0 && (pa < 0) != (pb < 0)) {
            r.push(solve_monotone(c, degree, ends[i], b, pa, pb));
        }
        pa = pb;
    }
    return r;
}

}  // namespace ltm
