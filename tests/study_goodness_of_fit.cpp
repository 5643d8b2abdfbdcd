// The goodness-of-fit tests of the dataset card (study/GoodnessOfFit.h): the Kolmogorov-Smirnov
// statistic and its p-value in every regime of Simard & L'Ecuyer's scheme, against closed forms,
// published values and the exact matrix; Pearson's chi-square p-value against its critical values;
// the requested laws' CDFs (study/Distribution.h).
#include <gtest/gtest.h>

#include <cmath>

#include "study/Distribution.h"
#include "study/GoodnessOfFit.h"
#include "tests/Tolerances.h"

using namespace ltm;

namespace {

// Relative difference.
double rel(double a, double b) { return std::fabs(a - b) / std::fabs(b); }

}  // namespace

TEST(KolmogorovSmirnov, TheStatisticIsTheLargestGapOfTheEmpiricalCdf) {
    // {0.6, 0.1, 0.5} against U(0, 1), sorted 0.1, 0.5, 0.6: the gaps above the empirical steps are
    // 1/3 - 0.1, 2/3 - 0.5, 1 - 0.6, those below 0.1 - 0, 0.5 - 1/3, 0.6 - 2/3: the largest 0.4.
    const auto u = [](double x) { return x; };
    EXPECT_NEAR(ks_statistic({0.6, 0.1, 0.5}, u), 0.4, 4 * tol::kEps);
    EXPECT_EQ(ks_statistic({}, u), 0.0);
    // One value x: D_1 = max(x, 1 - x).
    EXPECT_NEAR(ks_statistic({0.3}, u), 0.7, 4 * tol::kEps);
}

TEST(KolmogorovSmirnov, PValuesOfSmallSamplesMatchTheirClosedForms) {
    // n = 1: D_1 = max(U, 1 - U) >= d with probability 2 (1 - d) for d >= 1/2, 1 below.
    for (double d : {0.5, 0.6, 0.75, 0.9, 0.99}) EXPECT_LT(rel(ks_pvalue(1, d), 2 * (1 - d)), 8 * tol::kEps) << d;
    EXPECT_EQ(ks_pvalue(1, 0.3), 1.0);
    // Ruben & Gambino (1982): P(D_n < d) = n! / n^n (2 n d - 1)^n for 1/(2n) < d <= 1/n, and
    // P(D_n >= d) = 2 (1 - d)^n for d >= 1 - 1/n. n = 5, d = 0.15: 1 - 120/3125 * 0.5^5 = 0.9988;
    // d = 0.9: 2e-5.
    EXPECT_LT(rel(ks_pvalue(5, 0.15), 0.9988), 8 * tol::kEps);
    EXPECT_LT(rel(ks_pvalue(5, 0.9), 2e-5), 8 * tol::kEps);
    EXPECT_EQ(ks_pvalue(5, 0.1), 1.0);  // n d <= 1/2: D_5 >= 1/10 always
    EXPECT_EQ(ks_pvalue(5, 1.0), 0.0);
    // d >= 1/2: 2 P(D_n^+ >= d) exactly (Birnbaum & Tingey). n = 3, d = 0.6: the sum runs over
    // j = 0, 1: 0.4^3 / 0.6 + 3 (1/15)^2 = 0.12, times d: 0.072, doubled: 0.144.
    EXPECT_LT(rel(ks_pvalue(3, 0.6), 0.144), 64 * tol::kEps);
}

TEST(KolmogorovSmirnov, TheExactMatrixGivesMarsagliaTsangWangsValue) {
    // Marsaglia, Tsang & Wang (2003), their example: K(10, 0.274) = 0.6284796154565043. About
    // 2n roundings in n!/n^n and 4 log2(n) matrix products of 5-term sums: < 100 eps.
    EXPECT_LT(rel(kolmogorov_cdf_exact(10, 0.274), 0.6284796154565043), 100 * tol::kEps);
    EXPECT_LT(rel(ks_pvalue(10, 0.274), 1 - 0.6284796154565043), 300 * tol::kEps);
    // At the ends of the matrix's range it meets the closed forms: n d = 0.75 (Ruben-Gambino) and
    // d >= 1/2 (2 P(D^+ >= d), exact there).
    EXPECT_LT(rel(kolmogorov_cdf_exact(5, 0.15), 1 - 0.9988), 1e-12);
    EXPECT_LT(rel(1 - kolmogorov_cdf_exact(3, 0.6), 0.144), 1e-12);
}

TEST(KolmogorovSmirnov, TheApproximationsStayCloseToTheExactMatrix) {
    // Pelz-Good, where ks_pvalue uses it (n > 140, n d^1.5 > 1.4, n d^2 < 2.2): Simard & L'Ecuyer
    // (2011) report 5 decimal digits; the series' next term is O(n^-2), largest at n = 141.
    for (long n : {141L, 400L, 1000L}) {
        const double lo = std::pow(1.4 / n, 2.0 / 3), hi = std::sqrt(2.2 / n);
        for (int i = 0; i <= 20; ++i) {
            const double d = lo + (hi - lo) * i / 20.0;
            EXPECT_NEAR(kolmogorov_cdf_pelz_good(n, d), kolmogorov_cdf_exact(n, d), 1e-5) << n << " " << d;
        }
    }
    // Miller's 2 P(D^+ >= d), where ks_pvalue uses it (n d^2 >= 2.2): off by P(D^+ >= d, D^- >= d),
    // below 1e-4 of p there.
    for (long n : {200L, 1000L})
        for (double nd2 : {2.2, 3.0, 5.0, 8.0}) {
            const double d = std::sqrt(nd2 / n), exact = 1 - kolmogorov_cdf_exact(n, d);
            EXPECT_LT(rel(ks_pvalue(n, d), exact), 1e-4) << n << " " << d;
        }
}

TEST(KolmogorovSmirnov, LargeSamplesMeetScipyAndKolmogorovsLimit) {
    // scipy.stats.kstwo.sf (scipy 1.10.1, Simard & L'Ecuyer's scheme as here, its one-sided tail by
    // its own algorithm): n = 600, d = 0.1 (Miller); n = 1000, d = 0.035 (Pelz-Good). The
    // Birnbaum-Tingey terms come from lgamma's of size n ln n, each off by ~eps n ln n: 1e-11
    // bounds it at n = 600.
    EXPECT_LT(rel(ks_pvalue(600, 0.1), 1.1239700624504987e-05), 1e-11);
    EXPECT_LT(rel(ks_pvalue(1000, 0.035), 0.16848479713738718), 1e-12);
    // Kolmogorov's limit: P(sqrt(n) D_n >= x) -> Q(x) = 2 sum_k (-1)^(k-1) exp(-2 k^2 x^2); x =
    // 1.3580986 is its 5 % point. The first correction is K1(x) / sqrt(n) (Pelz-Good) with
    // |K1(1.358)| < 0.05, so 1 / sqrt(n) bounds the difference with room.
    const double x = 1.3580986;
    double Q = 0;
    for (int k = 1; k <= 20; ++k) Q += 2 * (k % 2 ? 1 : -1) * std::exp(-2.0 * k * k * x * x);
    EXPECT_NEAR(Q, 0.05, 1e-7);
    const long n = 10000000;
    EXPECT_NEAR(ks_pvalue(n, x / std::sqrt(static_cast<double>(n))), Q, 1 / std::sqrt(static_cast<double>(n)));
    // p falls as d grows, in every regime and across their boundaries.
    for (long m : {3L, 50L, 140L, 141L, 5000L, 200000L}) {
        double last = 1.0;
        for (int i = 1; i < 400; ++i) {
            const double d = i / 400.0, p = ks_pvalue(m, d);
            EXPECT_LE(p, last + 1e-9) << m << " " << d;
            EXPECT_GE(p, 0.0);
            last = p;
        }
    }
}

TEST(ChiSquare, PValuesAtTheTextbookCriticalValues) {
    // The 5 % points of chi-square with 1 to 5 degrees of freedom (scipy.stats.chi2.isf(0.05, nu)).
    const double x[] = {3.8414588206941285, 5.991464547107983, 7.814727903251178, 9.487729036781158, 11.070497693516355};
    for (int nu = 1; nu <= 5; ++nu) EXPECT_LT(rel(chi_square_pvalue(x[nu - 1], nu), 0.05), 1e-12) << nu;
    // nu = 2: exactly exp(-x / 2).
    EXPECT_LT(rel(chi_square_pvalue(3.0, 2), std::exp(-1.5)), 4 * tol::kEps);
    EXPECT_EQ(chi_square_pvalue(0.0, 1), 1.0);
    // Many degrees of freedom, where e^(-x / 2) alone underflows (x > 1490): scipy.stats.chi2.sf.
    // Each term is exp(L), L = a log y - y - lgamma(a + 1) from three parts of up to 15000 here, so
    // L is good to about 4 eps 15000 = 1.3e-11 absolute and the term, and the sum of such
    // positive terms, to that relative: 2e-11.
    EXPECT_LT(rel(chi_square_pvalue(2000, 2000), 0.4957947558197845), 2e-11);
    EXPECT_LT(rel(chi_square_pvalue(1600, 1501), 0.03747898979858334), 2e-11);
    EXPECT_LT(rel(chi_square_pvalue(3000, 2000), 2.204698611389594e-43), 2e-11);
}

TEST(Distributions, CdfsOfTheRequestedLaws) {
    using K = Distribution::Kind;
    using R = Distribution::Range;
    const Distribution u{K::Uniform, 2, 5}, lu{K::LogUniform, 0.1, 0.4}, c = Distribution::constant(0.3);
    EXPECT_NEAR(u.cdf(3.5), 0.5, 4 * tol::kEps);
    EXPECT_EQ(u.cdf(1.0), 0.0);
    EXPECT_EQ(u.cdf(6.0), 1.0);
    EXPECT_NEAR(lu.cdf(0.2), 0.5, 4 * tol::kEps);  // the median of a log-uniform is sqrt(a b)
    EXPECT_EQ(c.cdf(0.29), 0.0);
    EXPECT_EQ(c.cdf(0.3), 1.0);
    EXPECT_FALSE(c.continuous());
    // A normal (0.1, 0.1) truncated to positive values: P(X <= 0.1) = 1 - (1/2) / Phi(1) = 0.40571...
    const Distribution n{K::Normal, 0.1, 0.1, R::Positive};
    EXPECT_LT(rel(n.cdf(0.1), 0.4057132913274699), 1e-14);
    EXPECT_EQ(n.cdf(-1.0), 0.0);
    EXPECT_FALSE(n.admits(0.0));
    EXPECT_TRUE(n.admits(1e-300));
    // Untruncated: Phi.
    const Distribution m{K::Normal, 0.0, 2.0};
    EXPECT_NEAR(m.cdf(0.0), 0.5, 4 * tol::kEps);
}
