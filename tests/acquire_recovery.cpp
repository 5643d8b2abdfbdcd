// Sparse recovery (acquire/Recovery.h): OMP recovers every row with fewer nonzeros than Tropp's
// coherence guarantee exactly, from the number of +-1 patterns the Hoeffding bound says is
// enough; and the compressive acquisition recovers such rows of a T exactly (noise-free).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "acquire/Acquisition.h"
#include "acquire/CounterRng.h"
#include "acquire/Patterns.h"
#include "acquire/Recovery.h"
#include "tests/Tolerances.h"

namespace {

using namespace ltm;
using namespace ltm::acquire;

// K(s, n, delta) = ceil(2 (2 s - 1)^2 ln(n^2 / delta)): s = 2, n = 64, delta = 0.01 gives
// 2 * 9 * ln(409600) = 18 * 12.9229 = 232.6 -> 233.
TEST(Recovery, TheoreticalPatternCount) {
    EXPECT_EQ(compressive_patterns(2, 64, 0.01), 233);
    EXPECT_EQ(compressive_patterns(1, 64, 0.01), static_cast<int>(std::ceil(2 * std::log(4096 / 0.01))));
}

// The dictionary of n display pixels seen through K Bernoulli patterns, +-1 (2 x - 1): the
// patterns bernoulli_block draws.
std::vector<double> plus_minus_dictionary(int K, int n, std::uint64_t seed) {
    const PatternBlock b = bernoulli_block(1, n, K, seed);
    std::vector<double> A(static_cast<std::size_t>(K) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < K; ++i) A[static_cast<std::size_t>(j) * K + i] = b.on(j, i) ? 1.0 : -1.0;
    return A;
}

// At K = compressive_patterns(s, n, delta), the dictionary's coherence is below 1 / (2 s - 1)
// with probability 1 - delta (it is checked: the seed is fixed), and then OMP must recover EVERY
// s-sparse vector exactly, whatever its signs and magnitudes (Tropp 2004, Theorem A): the support
// exactly, the values to the least-squares rounding (Tolerances.h, omp_coefficient).
TEST(Recovery, OmpIsExactBelowTheCoherenceGuaranteeAtTheTheoreticalPatternCount) {
    for (const int s : {1, 2, 3}) {
        const int n = 48;
        const double delta = 0.01;
        const int K = compressive_patterns(s, n, delta);
        const std::vector<double> A = plus_minus_dictionary(K, n, 1234 + s);
        const double mu = mutual_coherence(A, K, n);
        ASSERT_LT(mu, 1.0 / (2 * s - 1)) << "s = " << s << ", K = " << K << ": the probabilistic bound failed for this seed";
        CounterRng rng(99, static_cast<std::uint64_t>(s), 0);
        for (int trial = 0; trial < 200; ++trial) {
            // s distinct columns, values of either sign in [0.05, 1] in magnitude.
            std::vector<int> support;
            while (static_cast<int>(support.size()) < s) {
                const int j = static_cast<int>(rng.next() % n);
                if (std::find(support.begin(), support.end(), j) == support.end()) support.push_back(j);
            }
            std::vector<double> t(static_cast<std::size_t>(n), 0.0);
            for (int j : support) t[static_cast<std::size_t>(j)] = (rng.uniform() < 0.5 ? -1 : 1) * (0.05 + 0.95 * rng.uniform());
            std::vector<double> z(static_cast<std::size_t>(K), 0.0);
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < K; ++i) z[static_cast<std::size_t>(i)] += A[static_cast<std::size_t>(j) * K + i] * t[static_cast<std::size_t>(j)];
            OmpOptions o;
            o.max_atoms = s;
            const OmpResult r = omp(A, K, n, z, o);
            std::vector<int> got = r.support, want = support;
            std::sort(got.begin(), got.end());
            std::sort(want.begin(), want.end());
            ASSERT_EQ(got, want) << "s = " << s << ", trial " << trial;
            for (std::size_t i = 0; i < r.support.size(); ++i)
                EXPECT_NEAR(r.values[i], t[static_cast<std::size_t>(r.support[i])], tol::omp_coefficient(K, 1.0));
        }
    }
}

// Beyond the guarantee nothing is promised, but the test must be able to fail: with K = 4
// patterns and 3 nonzeros among 48 candidates some vectors are not recovered.
TEST(Recovery, FarTooFewPatternsFail) {
    const int K = 4, n = 48;
    const std::vector<double> A = plus_minus_dictionary(K, n, 5);
    int failures = 0;
    for (int trial = 0; trial < 50; ++trial) {
        std::vector<double> t(static_cast<std::size_t>(n), 0.0);
        t[static_cast<std::size_t>(trial % n)] = 1;
        t[static_cast<std::size_t>((trial * 7 + 3) % n)] += 0.5;
        t[static_cast<std::size_t>((trial * 13 + 5) % n)] += 0.25;
        std::vector<double> z(static_cast<std::size_t>(K), 0.0);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < K; ++i) z[static_cast<std::size_t>(i)] += A[static_cast<std::size_t>(j) * K + i] * t[static_cast<std::size_t>(j)];
        OmpOptions o;
        o.max_atoms = 3;
        const OmpResult r = omp(A, K, n, z, o);
        double err = 0;
        std::vector<double> est(static_cast<std::size_t>(n), 0.0);
        for (std::size_t i = 0; i < r.support.size(); ++i) est[static_cast<std::size_t>(r.support[i])] = r.values[i];
        for (int j = 0; j < n; ++j) err = std::max(err, std::fabs(est[static_cast<std::size_t>(j)] - t[static_cast<std::size_t>(j)]));
        failures += err > 1e-6;
    }
    EXPECT_GT(failures, 0);
}

// The whole compressive acquisition, noise-free, on a 16 x 16 display: rows of at most 2 entries;
// stripes 2 wide leave at most (2 x 2)^2 = 16 candidates per row, and the random block has
// compressive_patterns(2, 16, 0.01) = 183 patterns; every row's entries (hence ScatterCount) come
// back exactly, values to float rounding.
TEST(Recovery, NoiseFreeCompressiveAcquisitionRecoversSparseRowsExactly) {
    const int P = 16, Q = 16;
    const DisplayGrid display{Q, P, 32.0, 32.0};
    CsrMatrix T;
    T.cols = P * Q;
    T.indptr.push_back(0);
    CounterRng rng(3, 4, 5);
    const int rows = 60;
    for (int k = 0; k < rows; ++k) {
        std::vector<int> cols;
        const int s = 1 + k % 2;
        while (static_cast<int>(cols.size()) < s) {
            const int l = static_cast<int>(rng.next() % (P * Q));
            if (std::find(cols.begin(), cols.end(), l) == cols.end()) cols.push_back(l);
        }
        std::sort(cols.begin(), cols.end());
        for (int l : cols) {
            T.indices.push_back(l);
            T.data.push_back(static_cast<float>(0.1 + 0.8 * rng.uniform()));
        }
        T.indptr.push_back(static_cast<std::int64_t>(T.data.size()));
    }
    T.rows = rows;
    AcquireOptions o;
    o.method = Method::Compressive;
    o.stripe_width = 2;
    o.patterns = (P / 2 + Q / 2) + compressive_patterns(2, 16, 0.01);
    o.threads = 1;
    SensorModel s;
    s.noise_free = true;
    const AcquireResult r = run_acquisition(T, rows, 1, display, o, s);
    FeatureOptions fo;
    fo.dark_block = std::min(o.dark_block, 16);  // as run_acquisition clamps it
    const FeatureImages exact = compute_features(T, rows, 1, display, fo);
    for (const char* ch : {"ScatterCount", "ScatterWidth", "ScatterDiameter"})
        for (int k = 0; k < rows; ++k)
            EXPECT_EQ(r.features.channel(ch)[static_cast<std::size_t>(k)], exact.channel(ch)[static_cast<std::size_t>(k)]) << ch << " row " << k;
    for (int k = 0; k < rows; ++k)
        EXPECT_NEAR(r.features.channel("BrightField")[static_cast<std::size_t>(k)], exact.channel("BrightField")[static_cast<std::size_t>(k)],
                    tol::omp_coefficient(o.patterns, 2.0) + tol::float_sum(2.0));
}

}  // namespace
