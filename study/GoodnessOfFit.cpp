#include "study/GoodnessOfFit.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "geometry/Vec3.h"

namespace ltm {

namespace {

// A square matrix times a power of two: value = m * 2^exponent. Durbin's matrix power overflows a
// double for large n; scaling by powers of two keeps every product exact.
struct ScaledMatrix {
    int size = 0;
    std::vector<double> m;
    long exponent = 0;
    double& at(int i, int j) { return m[static_cast<size_t>(i) * size + j]; }
    double at(int i, int j) const { return m[static_cast<size_t>(i) * size + j]; }
};

ScaledMatrix multiply(const ScaledMatrix& a, const ScaledMatrix& b) {
    const int s = a.size;
    ScaledMatrix c{s, std::vector<double>(static_cast<size_t>(s) * s, 0.0), a.exponent + b.exponent};
    for (int i = 0; i < s; ++i)
        for (int k = 0; k < s; ++k) {
            const double x = a.at(i, k);
            if (x == 0) continue;
            for (int j = 0; j < s; ++j) c.at(i, j) += x * b.at(k, j);
        }
    // Largest entry back into [0.5, 1) (an exact rescaling).
    double largest = 0;
    for (double v : c.m) largest = std::max(largest, std::fabs(v));
    if (largest > 0) {
        int e = 0;
        std::frexp(largest, &e);
        for (double& v : c.m) v = std::ldexp(v, -e);
        c.exponent += e;
    }
    return c;
}

// P(D_n^+ >= d), Birnbaum & Tingey (1951): the terms are positive, summed from their logarithms;
// 1 - d - j/n and d + j/n are formed as ((n - j) - n d) / n and (n d + j) / n, which keeps the
// first's relative precision where it is small.
double smirnov_upper(long n, double d) {
    if (!(d > 0)) return 1;
    if (d >= 1) return 0;
    const double N = static_cast<double>(n), nd = N * d;
    const long jmax = static_cast<long>(std::floor(N - nd));
    const double log_n_factorial = std::lgamma(N + 1);
    double sum = 0;
    for (long j = 0; j <= jmax && j <= n; ++j) {
        const double J = static_cast<double>(j);
        const double a = ((N - J) - nd) / N, b = (nd + J) / N;
        if (!(a > 0)) continue;  // 0^(n - j) with n - j >= 1
        const double log_term = log_n_factorial - std::lgamma(J + 1) - std::lgamma(N - J + 1) + (J - 1) * std::log(b) +
                                (N - J) * std::log(a);
        sum += std::exp(log_term);
    }
    return std::min(1.0, d * sum);
}

}  // namespace

double ks_statistic(std::vector<double> values, const std::function<double(double)>& cdf) {
    std::sort(values.begin(), values.end());
    const double n = static_cast<double>(values.size());
    double d = 0;
    for (size_t i = 0; i < values.size(); ++i) {
        const double f = cdf(values[i]);
        d = std::max({d, static_cast<double>(i + 1) / n - f, f - static_cast<double>(i) / n});
    }
    return d;
}

double kolmogorov_cdf_exact(long n, double d) {
    if (n < 1) throw std::invalid_argument("kolmogorov_cdf_exact: n must be at least 1");
    if (!(d > 0)) return 0;
    if (d >= 1) return 1;
    // Marsaglia, Tsang & Wang (2003): with n d = k - h (k a positive integer, 0 < h <= 1) and
    // m = 2k - 1, P(D_n < d) = n! / n^n (H^n)_{kk} for the m x m matrix
    //   H_ij = 1 / (i - j + 1)! for i - j + 1 >= 0 (0 above), except the first column,
    //   H_i1 = (1 - h^i) / i!, the last row, H_mj = (1 - h^(m - j + 1)) / (m - j + 1)!, and
    //   H_m1 = (1 - 2 h^m + max(0, 2h - 1)^m) / m!   (indices from 1).
    const double nd = static_cast<double>(n) * d;
    const long k = static_cast<long>(std::floor(nd)) + 1;
    const int m = static_cast<int>(2 * k - 1);
    const double h = static_cast<double>(k) - nd;
    ScaledMatrix H{m, std::vector<double>(static_cast<size_t>(m) * m, 0.0), 0};
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
            if (i - j + 1 >= 0) H.at(i, j) = 1;
    for (int i = 0; i < m; ++i) {
        H.at(i, 0) -= std::pow(h, i + 1);
        H.at(m - 1, i) -= std::pow(h, m - i);
    }
    if (2 * h - 1 > 0) H.at(m - 1, 0) += std::pow(2 * h - 1, m);
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
            for (int g = 1; g <= i - j + 1; ++g) H.at(i, j) /= g;
    // H^n by squaring.
    ScaledMatrix power = H, result{m, std::vector<double>(static_cast<size_t>(m) * m, 0.0), 0};
    for (int i = 0; i < m; ++i) result.at(i, i) = 1;
    for (long e = n; e > 0; e >>= 1) {
        if (e & 1) result = multiply(result, power);
        if (e > 1) power = multiply(power, power);
    }
    // Times n! / n^n, one factor i / n at a time, renormalised by powers of two.
    double s = result.at(static_cast<int>(k - 1), static_cast<int>(k - 1));
    long exponent = result.exponent;
    for (long i = 1; i <= n; ++i) {
        s *= static_cast<double>(i) / static_cast<double>(n);
        int e = 0;
        s = std::frexp(s, &e);
        exponent += e;
    }
    if (exponent < -2000) return 0;
    return std::min(1.0, std::ldexp(s, static_cast<int>(std::min<long>(exponent, 2000))));
}

double kolmogorov_cdf_pelz_good(long n, double d) {
    if (!(d > 0)) return 0;
    if (d >= 1) return 1;
    // Pelz & Good (1976), as Simard & L'Ecuyer (2011) give it: with z = sqrt(n) d,
    //   P(D_n < d) ~ K0(z) + K1(z) / n^(1/2) + K2(z) / n + K3(z) / n^(3/2),
    // sums over odd m = 2k - 1 of polynomials in m^2 times q^(m^2), q = exp(-pi^2 / (8 z^2)), and
    // for K2, K3 also over all k of k^2 exp(-pi^2 k^2 / (2 z^2)).
    const double z = std::sqrt(static_cast<double>(n)) * d;
    const double z2 = z * z, z4 = z2 * z2, z6 = z4 * z2, z8 = z4 * z4;
    const double pi2 = kPi * kPi, pi4 = pi2 * pi2, pi6 = pi4 * pi2;
    if (-pi2 / (8 * z2) < -708) return 0;  // q^1 underflows: z < 0.042
    const int kmax = static_cast<int>(std::ceil(16 * z / kPi)) + 1;
    double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    for (int k = 1; k <= kmax; ++k) {
        const double mo = 2.0 * k - 1, m2 = mo * mo, m4 = m2 * m2, m6 = m4 * m2;
        const double q = std::exp(-pi2 * m2 / (8 * z2));
        s0 += q;
        s1 += (pi2 * m2 / 4 - z2) * q;
        s2 += (6 * z6 + 2 * z4 + pi2 * (2 * z4 - 5 * z2) * m2 / 4 + pi4 * (1 - 2 * z2) * m4 / 16) * q;
        s3 += (-30 * z6 - 90 * z8 + pi2 * (135 * z4 - 96 * z6) * m2 / 4 + pi4 * (212 * z4 - 60 * z2) * m4 / 16 +
               pi6 * (5 - 30 * z2) * m6 / 64) *
              q;
    }
    double t2 = 0, t3 = 0;
    for (int k = 1; k <= kmax; ++k) {
        const double kk = static_cast<double>(k) * k;
        const double w = kk * std::exp(-pi2 * kk / (2 * z2));
        t2 += w;
        t3 += (3 * z2 - pi2 * kk) * w;
    }
    const double r = std::sqrt(2 * kPi);
    const double K0 = r / z * s0;
    const double K1 = r / (6 * z4) * s1;
    const double K2 = r / (72 * z * z6) * s2 - r * pi2 / (36 * z * z2) * t2;
    const double K3 = r / (6480 * z4 * z6) * s3 + r * pi2 / (216 * z6) * t3;
    const double rn = std::sqrt(static_cast<double>(n));
    return std::clamp(K0 + K1 / rn + K2 / (rn * rn) + K3 / (rn * rn * rn), 0.0, 1.0);
}

double ks_pvalue(long n, double d) {
    if (n < 1) throw std::invalid_argument("ks_pvalue: n must be at least 1");
    if (!(d > 0)) return 1;
    if (d >= 1) return 0;
    const double N = static_cast<double>(n), t = N * d;
    if (t <= 0.5) return 1;
    if (t <= 1) {
        // Ruben & Gambino: P(D_n < d) = prod_{i=1..n} (i / n) (2t - 1).
        double s = 1;
        for (long i = 1; i <= n && s > 1e-300; ++i) s *= static_cast<double>(i) / N * (2 * t - 1);
        return 1 - s;
    }
    if (t >= N - 1) return 2 * std::pow(1 - d, N);
    if (d >= 0.5) return 2 * smirnov_upper(n, d);
    const double nd2 = t * d;
    if (n <= 140) return nd2 < 4 ? 1 - kolmogorov_cdf_exact(n, d) : 2 * smirnov_upper(n, d);
    if (nd2 >= 370) return 0;  // below 2 exp(-740)
    if (nd2 >= 2.2) return std::min(1.0, 2 * smirnov_upper(n, d));
    if (n <= 100000 && N * std::pow(d, 1.5) <= 1.4) return 1 - kolmogorov_cdf_exact(n, d);
    return 1 - kolmogorov_cdf_pelz_good(n, d);
}

double chi_square_pvalue(double x, int nu) {
    if (nu < 1) throw std::invalid_argument("chi_square_pvalue: at least one degree of freedom");
    if (!(x > 0)) return 1;
    const double y = 0.5 * x, log_y = std::log(y);
    // Q(nu/2, y): even nu = 2m, e^-y sum_{j<m} y^j / j!  (A&S 26.4.5 via 6.5.13);
    // odd nu = 2m + 1, erfc(sqrt y) + e^-y sum_{j<m} y^(j+1/2) / Gamma(j + 3/2)  (A&S 26.4.4).
    // Each term y^a e^-y / Gamma(a + 1) is taken from its logarithm: e^-y alone underflows for
    // y > 745 while the terms near a = y are of order 1 / sqrt y (nu = x = 2000 gives 0.496).
    const auto term = [&](double a) { return std::exp(a * log_y - y - std::lgamma(a + 1)); };
    double sum = 0;
    if (nu % 2 == 0) {
        for (int j = 0; j < nu / 2; ++j) sum += term(j);
    } else {
        sum = std::erfc(std::sqrt(y));
        for (int j = 0; j < (nu - 1) / 2; ++j) sum += term(j + 0.5);
    }
    return std::min(1.0, sum);
}

}  // namespace ltm
