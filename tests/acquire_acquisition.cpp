// The simulated acquisition (acquire/Acquisition.h): bit-identical for any thread count, a new
// seed a new noise realisation; noise-free, the references (bright and dark field, brute force)
// give the exact features of T.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "acquire/Acquisition.h"
#include "acquire/CounterRng.h"
#include "acquire/Instrument.h"
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

// The bright field beside every acquisition is the reference a CNR is judged against: the same
// image for every method and K (its noise streams are kBrightFieldPattern's), so a defect's
// bright-field CNR does not move with the method the acquisition happens to use.
TEST(Acquisition, TheBrightFieldReferenceIsTheSameImageForEveryMethod) {
    const CsrMatrix T = random_T();
    SensorModel s;
    std::vector<float> first;
    struct Run { Method m; int K; };
    for (const Run run : {Run{Method::Fields, 2}, Run{Method::Gray, 2 * (5 + 4)}, Run{Method::Gray, 2 * (5 + 4) + 6},
                          Run{Method::Stripes, kP + kQ}, Run{Method::Stripes, 4}}) {
        AcquireOptions o;
        o.method = run.m;
        o.patterns = run.K;
        o.dark_block = 6;
        const AcquireResult r = run_acquisition(T, kRows, 1, kDisplay, o, s);
        const std::vector<float>& bf = r.bright.channel("BrightField");
        if (first.empty()) first = bf;
        EXPECT_EQ(bf, first) << method_name(run.m) << " K = " << run.K;
    }
    // Another noise seed, another image.
    s.seed = 2;
    AcquireOptions o;
    o.method = Method::Fields;
    o.patterns = 2;
    o.dark_block = 6;
    EXPECT_NE(run_acquisition(T, kRows, 1, kDisplay, o, s).bright.channel("BrightField"), first);
}

// check_patterns suggests the counts nearest a K that stripes cannot show, each with the stripe
// width that count is shown with (stripe_width_for's, what run_acquisition uses). On 500 x 500, 7
// lies between 6 (w = 167) and 8, which 4 + 4 stripes of 125 pixels show (widths 125 to 166 all
// give 8 patterns; 8 patterns mean 125).
TEST(Acquisition, StripeSuggestionsNameTheWidthsTheirCountsUse) {
    AcquireOptions o;
    o.method = Method::Stripes;
    o.patterns = 7;
    const std::string m = check_patterns(o, 500, 500);
    EXPECT_NE(m.find("the nearest are 6 (w = 167) and 8 (w = 125)"), std::string::npos) << m;
    EXPECT_EQ(stripe_width_for(8, 500, 500), 125);
    // Every suggestion on a few displays: each count is one stripes shows, with that width.
    const std::regex nearest(R"(the nearest are (\d+) \(w = (\d+)\) and (\d+) \(w = (\d+)\))");
    for (const auto& [P, Q] : {std::pair{500, 500}, std::pair{12, 20}, std::pair{37, 91}}) {
        int suggestions = 0;
        for (int K = 1; K <= P + Q; ++K) {
            o.patterns = K;
            const std::string msg = check_patterns(o, P, Q);
            if (msg.empty()) continue;
            std::smatch g;
            ASSERT_TRUE(std::regex_search(msg, g, nearest)) << msg;
            for (int i : {1, 3}) {
                const int count = std::stoi(g[i].str()), w = std::stoi(g[i + 1].str());
                EXPECT_EQ(stripe_width_for(count, P, Q), w) << P << " x " << Q << ", K = " << K << ": " << msg;
                o.patterns = count;
                EXPECT_EQ(check_patterns(o, P, Q), "") << count;
            }
            ++suggestions;
        }
        EXPECT_GT(suggestions, 0);
    }
}

}  // namespace

// Every channel compute_features makes has an instrument (acquire/Instrument.h's table): a feature
// added without one would be measured by nothing, and the experiment's measured table would have
// no number for it. The deflection channels are measured through MeanX and MeanY.
TEST(Instrument, EveryFeatureChannelHasAnInstrument) {
    for (const std::string& ch : ltm::feature_channel_names(false)) {
        const ltm::acquire::AcquireOptions o = ltm::acquire::instrument_for(ch, 500, 500);
        EXPECT_GE(o.patterns, 1) << ch;
    }
    EXPECT_THROW(ltm::acquire::instrument_for("NoSuchChannel", 500, 500), std::invalid_argument);
}
