// The simulated acquisition (acquire/Acquisition.h): bit-identical for any thread count, a new
// seed a new noise realisation; noise-free, the references (bright and dark field, brute force)
// give the exact features of T.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "acquire/Acquisition.h"
#include "acquire/CounterRng.h"
#include "tests/Tolerances.h"

namespace {

using namespace ltm;
using namespace ltm::acquire;

constexpr int kP = 12, kQ = 20, kRows = 300;
const DisplayGrid kDisplay{kQ, kP, 40.0, 24.0};

// A random T: row k has 0 .. 5 entries anywhere on the display (some rows empty).
CsrMatrix random_T() {
    CsrMatrix T;
    T.rows = kRows;
    T.cols = kP * kQ;
    T.indptr.push_back(0);
    CounterRng rng(17, 0, 0);
    for (int k = 0; k < kRows; ++k) {
        std::vector<int> cols;
        const int n = static_cast<int>(rng.next() % 6);
        for (int i = 0; i < n; ++i) cols.push_back(static_cast<int>(rng.next() % (kP * kQ)));
        std::sort(cols.begin(), cols.end());
        cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
        for (int l : cols) {
            T.indices.push_back(l);
            T.data.push_back(static_cast<float>(0.05 + 0.3 * rng.uniform()));
        }
        T.indptr.push_back(static_cast<std::int64_t>(T.data.size()));
    }
    return T;
}

// A noise-free acquisition of random_T() with a black display (b = 0) by `method` with K patterns,
// and the exact features of the same T (dark block 6 for both).
std::pair<AcquireResult, FeatureImages> noise_free_reference(Method method, int K) {
    const CsrMatrix T = random_T();
    SensorModel s;
    s.noise_free = true;
    s.display.black_level = 0;
    AcquireOptions o;
    o.method = method;
    o.patterns = K;
    o.dark_block = 6;
    FeatureOptions fo;
    fo.dark_block = 6;
    return {run_acquisition(T, kRows, 1, kDisplay, o, s), compute_features(T, kRows, 1, kDisplay, fo)};
}

TEST(Acquisition, BitIdenticalForAnyThreadCountAndNewNoiseForANewSeed) {
    const CsrMatrix T = random_T();
    SensorModel s;
    const PatternBlock X = bernoulli_block(kP, kQ, 130, 5);  // more than two 64-bit words per pixel
    const Measurements one = simulate(T, X, s, 0, 1), two = simulate(T, X, s, 0, 2), all = simulate(T, X, s, 0, 0);
    EXPECT_EQ(one.values, two.values);
    EXPECT_EQ(one.values, all.values);
    s.seed = 2;
    const Measurements other = simulate(T, X, s, 0, 2);
    EXPECT_NE(one.values, other.values);
    // A grey block too.
    s.seed = 1;
    const PatternBlock G = phase_block(kP, kQ, 4, 8, s.display);
    EXPECT_EQ(simulate(T, G, s, 7, 1).values, simulate(T, G, s, 7, 2).values);
}

// Noise-free, y_j = T L(x_j) exactly up to rounding: all on gives the row sum (BrightField), the
// dark-field pattern b s + (1 - b) T x_dark; with b = 0 the features' own DarkField.
TEST(Acquisition, NoiseFreeFieldsAreTheExactBrightAndDarkField) {
    const auto [r, exact] = noise_free_reference(Method::Fields, 2);
    for (const char* ch : {"BrightField", "DarkField"})
        for (int k = 0; k < kRows; ++k) {
            const double want = exact.channel(ch)[static_cast<std::size_t>(k)];
            EXPECT_NEAR(r.features.channel(ch)[static_cast<std::size_t>(k)], want,
                        tol::radiance_sum(2.0) + tol::float_sum(2.0)) << ch << " " << k;
        }
}

// Noise-free brute force measures every T[k, l] (black level subtracted), so the features of its
// T-hat are those of T: counts and extents exactly.
TEST(Acquisition, NoiseFreeBruteForceGivesTheExactFeatures) {
    const auto [r, exact] = noise_free_reference(Method::BruteForce, kP * kQ);
    for (const char* ch : {"ScatterCount", "ScatterWidth", "ScatterRows", "ScatterColumns", "ScatterDiameter"})
        for (int k = 0; k < kRows; ++k)
            EXPECT_EQ(r.features.channel(ch)[static_cast<std::size_t>(k)], exact.channel(ch)[static_cast<std::size_t>(k)])
                << ch << " " << k;
}

// Under noise the estimates scatter around the truth; a dim single-pixel row far below the noise
// is not seen by the line scan (no false extent from noise alone at 5 sigma).
TEST(Acquisition, LineScanUnderNoiseSeesBrightEntriesAndNoNoise) {
    CsrMatrix T;
    T.rows = 2;
    T.cols = kP * kQ;
    T.indptr = {0, 2, 2};
    T.indices = {3 * kQ + 4, 9 * kQ + 15};
    T.data = {0.4f, 0.3f};
    SensorModel s;
    AcquireOptions o;
    o.method = Method::Stripes;
    o.patterns = kP + kQ;
    const AcquireResult r = run_acquisition(T, 2, 1, kDisplay, o, s);
    EXPECT_EQ(r.features.channel("ScatterRows")[0], 6);
    EXPECT_EQ(r.features.channel("ScatterColumns")[0], 11);
    EXPECT_EQ(r.features.channel("ScatterRows")[1], 0);
    EXPECT_EQ(r.features.channel("ScatterColumns")[1], 0);
}

// Brute force under noise: a row holding one bright entry is measured over every display pixel;
// the dark ones must not turn up as entries more often than the threshold's design allows
// (Tolerances.h), and the bright entry must always be found.
TEST(Acquisition, BruteForceUnderNoiseFindsFewFalseEntries) {
    const int P = 100, Q = 100, rows = 400;
    const DisplayGrid display{Q, P, 100.0, 100.0};
    CsrMatrix T;
    T.rows = rows;
    T.cols = P * Q;
    T.indptr.push_back(0);
    for (int k = 0; k < rows; ++k) {
        T.indices.push_back((k * 37) % (P * Q));
        T.data.push_back(0.5f);
        T.indptr.push_back(k + 1);
    }
    SensorModel s;
    AcquireOptions o;
    o.method = Method::BruteForce;
    o.patterns = P * Q;
    const AcquireResult r = run_acquisition(T, rows, 1, display, o, s);
    int false_entries = 0, missed = 0;
    for (int k = 0; k < rows; ++k) {
        const float count = r.features.channel("ScatterCount")[static_cast<std::size_t>(k)];
        false_entries += count > 1 ? static_cast<int>(count) - 1 : 0;
        missed += count < 1;
    }
    EXPECT_LE(false_entries, tol::kBruteForceFalseEntries400Rows);
    EXPECT_EQ(missed, 0);  // 0.5 of the light is 2600 electrons, hundreds of sigma
}

}  // namespace
