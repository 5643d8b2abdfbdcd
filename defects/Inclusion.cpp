#include "defects/Inclusion.h"

#include <algorithm>
#include <cmath>

namespace ltm {

InclusionField::InclusionField(const Defect& d, double n_glass)
    : c_(d.center), e_(d.semi_axes), ft_(d.frame.transposed()), n0_(n_glass), dn_(d.delta_n),
      smooth_(d.index_profile == IndexProfile::Smooth) {
    inv_e2_ = {1.0 / (e_.x * e_.x), 1.0 / (e_.y * e_.y), 1.0 / (e_.z * e_.z)};
}

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

double InclusionField::curvature_bound(double s_lo, double s_hi) const {
    // q = (1 - s)^2 is largest at an end of [s_lo, s_hi]; s (1 - s)^2 peaks at s = 1/3 on [0, 1]
    // and increases beyond 1.
    const double q_max = std::max((1.0 - s_lo) * (1.0 - s_lo), (s_hi - 1.0) * (s_hi - 1.0));
    auto w = [](double t) { return t * (1.0 - t) * (1.0 - t); };
    double w_max = std::max(w(s_lo), w(s_hi));
    if (s_lo <= 1.0 / 3.0 && 1.0 / 3.0 <= s_hi) w_max = s_hi > 1.0 ? std::max(w(1.0 / 3.0), w(s_hi)) : w(1.0 / 3.0);
    const double emin = min_semi_axis(), e2 = emin * emin;
    const double d2q = (s_hi <= 1.0 ? 4.0 * (1.0 + s_hi) : 12.0 * s_hi - 4.0) / e2;
    const double gq2 = 16.0 * w_max / e2;
    const double adn = std::fabs(dn_);
    return 2.0 * adn * (std::fabs(n0_) + adn * q_max) * d2q + 2.0 * dn_ * dn_ * gq2;
}

double InclusionField::hessian_bound(const Vec3& centre, double radius) const {
    if (!smooth_) return 0.0;
    const double emin = min_semi_axis();
    const double rho_c = std::sqrt(s(centre));
    const double rho_lo = std::max(0.0, rho_c - radius / emin), rho_hi = rho_c + radius / emin;
    if (rho_lo >= 1.0) return 0.0;  // the ball lies outside the inclusion: n is constant there
    return curvature_bound(rho_lo * rho_lo, std::min(1.0, rho_hi * rho_hi));
}

double InclusionField::extended_n2(const Vec3& x, double s_ext) const {
    const double r2 = s(x);
    if (!smooth_ || !(r2 < s_ext)) return n2(x);
    const double n = n0_ + dn_ * (1.0 - r2) * (1.0 - r2);
    return n * n;
}

double InclusionField::extended_laplacian_n2(const Vec3& x, double s_ext) const {
    const double r2 = s(x);
    if (!smooth_ || !(r2 < s_ext)) return 0.0;
    const Vec3 y = ft_ * (x - c_);
    const Vec3 sy{y.x * inv_e2_.x, y.y * inv_e2_.y, y.z * inv_e2_.z};
    const double grad_s2 = 4.0 * length2(sy), lap_s = 2.0 * (inv_e2_.x + inv_e2_.y + inv_e2_.z);
    const double u = 1.0 - r2, q = u * u;
    const double lap_q = 2.0 * grad_s2 - 2.0 * u * lap_s, grad_q2 = 4.0 * q * grad_s2;
    return 2.0 * dn_ * (n0_ + dn_ * q) * lap_q + 2.0 * dn_ * dn_ * grad_q2;
}

Mat3 InclusionField::extended_hessian_n2(const Vec3& x, double s_ext) const {
    const double r2 = s(x);
    if (!smooth_ || !(r2 < s_ext)) return Mat3::zero();
    const Vec3 y = ft_ * (x - c_);
    const Mat3 f = ft_.transposed();
    const Vec3 gs = f * Vec3{2.0 * y.x * inv_e2_.x, 2.0 * y.y * inv_e2_.y, 2.0 * y.z * inv_e2_.z};
    const double u = 1.0 - r2, q = u * u;
    const Vec3 gq = gs * (-2.0 * u);
    Mat3 h = Mat3::zero();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double d2s = 0;  // (2 F S F^T)_ij
            for (int k = 0; k < 3; ++k) d2s += 2.0 * f(i, k) * inv_e2_[k] * f(j, k);
            const double d2q = 2.0 * gs[i] * gs[j] - 2.0 * u * d2s;
            h(i, j) = 2.0 * dn_ * (n0_ + dn_ * q) * d2q + 2.0 * dn_ * dn_ * gq[i] * gq[j];
        }
    return h;
}

double InclusionField::extended_hessian_bound(const Vec3& centre, double radius, double s_ext) const {
    if (!smooth_) return 0.0;
    if (!(s_ext > 1.0)) return hessian_bound(centre, radius);
    const double emin = min_semi_axis();
    const double rho_c = std::sqrt(s(centre));
    const double rho_lo = std::max(0.0, rho_c - radius / emin), rho_hi = rho_c + radius / emin;
    if (rho_lo >= 1.0) return 0.0;  // outside the ellipsoid: no path uses the mesh there
    const double s_hi = rho_hi * rho_hi;
    double m = curvature_bound(rho_lo * rho_lo, s_hi);
    if (s_hi > s_ext) {
        const double q = (s_hi - 1.0) * (s_hi - 1.0), adn = std::fabs(dn_);
        const double jump = 2.0 * std::fabs(n0_) * adn * q + dn_ * dn_ * q * q;
        m += radius > 0 ? 2.0 * jump / (radius * radius) : 0.0;
    }
    return m;
}

}  // namespace ltm
