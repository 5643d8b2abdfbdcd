#pragma once
// Goodness-of-fit tests for the dataset card (study/DatasetCard.h): does a sampled parameter follow
// the law the spec asked for?
//
// One-sample Kolmogorov-Smirnov. For n values x_(1) <= ... <= x_(n) and a continuous CDF F,
//   D_n = max_i max(i / n - F(x_(i)), F(x_(i)) - (i - 1) / n),
// the largest distance between the empirical CDF and F. Under the null hypothesis (the values are
// independent draws from F) D_n's law does not depend on F, and the p-value is P(D_n >= d).
// It is computed as Simard & L'Ecuyer recommend ("Computing the two-sided Kolmogorov-Smirnov
// distribution", J. Stat. Softw. 39(11), 2011), each piece from its source:
//   - n d <= 1/2: p = 1; 1/2 < n d <= 1: P(D_n < d) = n! / n^n (2 n d - 1)^n, and
//     n d >= n - 1: p = 2 (1 - d)^n (Ruben & Gambino 1982, exact);
//   - d >= 1/2, or n d^2 large (>= 4 for n <= 140, >= 2.2 beyond): p = 2 P(D_n^+ >= d), with the
//     one-sided tail exact by Birnbaum & Tingey (1951),
//       P(D_n^+ >= d) = d sum_{j=0}^{floor(n (1 - d))} C(n, j) (d + j/n)^(j-1) (1 - d - j/n)^(n-j);
//     exact for d >= 1/2 (D^+ and D^- cannot both reach d), and Miller's (1956) approximation
//     otherwise, whose error is P(D^+ >= d and D^- >= d), below 1e-4 p where it is used;
//   - otherwise 1 - P(D_n < d), with P(D_n < d) by Durbin's matrix (exact; evaluated as Marsaglia,
//     Tsang & Wang, "Evaluating Kolmogorov's distribution", J. Stat. Softw. 8(18), 2003) for
//     n <= 140, and for n <= 10^5 where n d^(3/2) <= 1.4; by the Pelz & Good (1976) asymptotic
//     series in 1/sqrt(n) (four terms) beyond, within about 1e-5 of the exact value there (tested
//     against the exact matrix where both apply).
//
// Pearson's chi-square for a word chosen from k options: X^2 = sum (O - E)^2 / E on k - 1 degrees
// of freedom; its p-value P(chi2_nu >= x) = Q(nu / 2, x / 2) is a finite sum for integer nu
// (Abramowitz & Stegun 26.4.4 and 26.4.5).
#include <functional>
#include <vector>

namespace ltm {

// D_n of `values` (in any order) against the continuous CDF `cdf`; 0 for no values.
double ks_statistic(std::vector<double> values, const std::function<double(double)>& cdf);

// P(D_n >= d) for n independent draws from a continuous law (n >= 1).
double ks_pvalue(long n, double d);

// P(D_n < d) by Durbin's matrix (Marsaglia, Tsang & Wang 2003): exact up to rounding, cost
// O(m^3 log n) with m = 2 floor(n d) + 1. Used by ks_pvalue where it applies; exposed for tests.
double kolmogorov_cdf_exact(long n, double d);

// P(D_n < d) by the Pelz-Good series (an approximation for large n). Exposed for tests.
double kolmogorov_cdf_pelz_good(long n, double d);

// P(chi2_nu >= x) for nu >= 1 degrees of freedom, by the finite series of A&S 26.4.4-5: nu / 2
// terms, each from its logarithm.
double chi_square_pvalue(double x, int nu);

}  // namespace ltm
