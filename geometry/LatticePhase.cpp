#include "geometry/LatticePhase.h"

#include <cmath>

namespace ltm {

namespace {

// The six plane families of BCC's Delaunay tetrahedra, m, and the axis orthogonal to each.
struct Family {
    Vec3 m;
    int axis;
};
constexpr Family kFamilies[6] = {{{1, 1, 0}, 2}, {{1, -1, 0}, 2}, {{1, 0, 1}, 1},
                                 {{1, 0, -1}, 1}, {{0, 1, 1}, 0}, {{0, 1, -1}, 0}};

// B2({t}) = u^2 - u + 1/6 with u the fractional part of t.
double bernoulli2(double t) {
    const double u = t - std::floor(t);
    return u * u - u + 1.0 / 6.0;
}

}  // namespace

Mat3 bcc_interpolation_moment(const Vec3& xi) {
    Mat3 s = Mat3::zero();
    for (int i = 0; i < 3; ++i) s(i, i) = 1.0 / 12.0;
    for (const Family& f : kFamilies) {
        const double b = 0.25 * bernoulli2(dot(f.m, xi));
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) s(i, j) -= b * f.m[i] * f.m[j];
        s(f.axis, f.axis) += b;
    }
    return s;
}

LatticePhase::LatticePhase(const LatticeFrame& frame) : frame_(frame), to_lattice_(frame.rotation.transposed()) {}

Vec3 LatticePhase::operator()(const Vec3& x, const Vec3& p, const Mat3& hessian) const {
    const double a = frame_.spacing;
    if (!(a > 0)) return {};
    const Vec3 xi = (to_lattice_ * x - frame_.origin) / a;
    const Vec3 pl = to_lattice_ * p;
    const double pn = length(pl);
    if (!(pn > 0) || !is_finite(xi)) return {};
    const Mat3 h = to_lattice_ * hessian * frame_.rotation;  // R^T H R
    Vec3 psi;
    for (const Family& f : kFamilies) {
        const double mp = dot(f.m, pl);
        if (std::fabs(mp) < kResonance * std::sqrt(2.0) * pn) continue;
        const double t = h(f.axis, f.axis) - dot(f.m, h * f.m);
        psi += f.m * (t * bernoulli2(dot(f.m, xi)) / mp);
    }
    return frame_.rotation * (psi * (a * a / 16.0));
}

}  // namespace ltm
