#include "defects/Inclusion.h"

#include <algorithm>
#include <cmath>

namespace ltm {

InclusionField::InclusionField(const Defect& d, double n_glass)
    : c_(d.center), e_(d.semi_axes), ft_(d.frame.transposed()), n0_(n_glass), dn_(d.delta_n),
      smooth_(d.index_profile == IndexProfile::Smooth) {}

double InclusionField::s(const Vec3& x) const {
    const Vec3 y = ft_ * (x - c_);
    const double a = y.x / e_.x, b = y.y / e_.y, c = y.z / e_.z;
    return a * a + b * b + c * c;
}

double InclusionField::n(const Vec3& x) const {
    const double r2 = s(x);
    if (!(r2 < 1.0)) return n0_;
    if (!smooth_) return n0_ + dn_;
    const double q = (1.0 - r2) * (1.0 - r2);
    return n0_ + dn_ * q;
}

double InclusionField::max_semi_axis() const { return std::max({e_.x, e_.y, e_.z}); }
double InclusionField::min_semi_axis() const { return std::min({e_.x, e_.y, e_.z}); }

double InclusionField::hessian_bound(const Vec3& centre, double radius) const {
    if (!smooth_) return 0.0;
    const double emin = min_semi_axis();
    const double rho_c = std::sqrt(s(centre));
    const double rho_lo = std::max(0.0, rho_c - radius / emin), rho_hi = rho_c + radius / emin;
    if (rho_lo >= 1.0) return 0.0;  // the ball lies outside the inclusion: n is constant there
    const double s_lo = rho_lo * rho_lo, s_hi = std::min(1.0, rho_hi * rho_hi);
    // q = (1 - s)^2 is largest at the smallest s; s (1 - s)^2 peaks at s = 1/3 on [0, 1].
    const double q_max = (1.0 - s_lo) * (1.0 - s_lo);
    auto w = [](double t) { return t * (1.0 - t) * (1.0 - t); };
    const double w_max = (s_lo <= 1.0 / 3.0 && 1.0 / 3.0 <= s_hi) ? w(1.0 / 3.0) : std::max(w(s_lo), w(s_hi));
    const double e2 = emin * emin;
    const double d2q = 4.0 * (1.0 + s_hi) / e2;
    const double gq2 = 16.0 * w_max / e2;
    const double adn = std::fabs(dn_);
    return 2.0 * adn * (std::fabs(n0_) + adn * q_max) * d2q + 2.0 * dn_ * dn_ * gq2;
}

}  // namespace ltm
