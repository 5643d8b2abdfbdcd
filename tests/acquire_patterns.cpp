// Pattern families and their decoders (acquire/Patterns.h), noise-free: Gray code (+ phase
// shifting) recovers the exact mean display position of single-pixel rows and the midpoint of a
// two-pixel row; line scans recover the exact row and column extents.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "acquire/Acquisition.h"
#include "acquire/Patterns.h"
#include "tests/Tolerances.h"

namespace {

using namespace ltm;
using namespace ltm::acquire;

// A T whose row k holds the given (column, value) entries (columns increasing).
CsrMatrix rows_matrix(const std::vector<std::vector<std::pair<int, float>>>& rows, std::int64_t cols) {
    CsrMatrix T;
    T.rows = static_cast<std::int64_t>(rows.size());
    T.cols = cols;
    T.indptr.push_back(0);
    for (const auto& r : rows) {
        for (const auto& [l, v] : r) {
            T.indices.push_back(l);
            T.data.push_back(v);
        }
        T.indptr.push_back(static_cast<std::int64_t>(T.data.size()));
    }
    return T;
}

// A P x Q display that is not a power of two either way (the Gray words have unused codes).
constexpr int kP = 5, kQ = 13;
const DisplayGrid kDisplay{kQ, kP, 26.0, 15.0};

double column_x(double q) { return -kDisplay.width / 2 + (q + 0.5) * kDisplay.width / kDisplay.Q; }
double row_y(double p) { return kDisplay.height / 2 - (p + 0.5) * kDisplay.height / kDisplay.P; }

SensorModel noise_free() {
    SensorModel s;
    s.noise_free = true;
    s.display.black_level = 0.01;  // the black level must cancel out
    s.display.bits = 16;
    return s;
}

// One camera pixel per display pixel, seeing only it (value 0.37: any value, the decoders must not
// depend on it).
CsrMatrix single_pixel_rows() {
    std::vector<std::vector<std::pair<int, float>>> rows;
    for (int l = 0; l < kP * kQ; ++l) rows.push_back({{l, 0.37f}});
    return rows_matrix(rows, kP * kQ);
}

TEST(Patterns, GrayCodeCountsAndInversePairs) {
    const PatternBlock b = gray_code_block(kP, kQ);
    EXPECT_EQ(b.K, 2 * (4 + 3));  // ceil log2 13 = 4, ceil log2 5 = 3
    for (long l = 0; l < b.pixels(); ++l)
        for (int j = 0; j < b.K; j += 2) EXPECT_NE(b.on(l, j), b.on(l, j + 1)) << "pattern and inverse at " << l;
    // Neighbouring columns differ in exactly one column bit (the Gray property).
    for (int q = 0; q + 1 < kQ; ++q) {
        int changed = 0;
        for (int i = 0; i < 4; ++i) changed += b.on(q, 2 * i) != b.on(q + 1, 2 * i);
        EXPECT_EQ(changed, 1) << q;
    }
}

// Gray code alone: bit i is (y+ > y-); for a single-pixel row y+ - y- = (1 - b) t (+-1), so every
// bit is the pixel's own and the decoded column is q exactly: the mean position is
// -W/2 + (q + 1/2) W / Q, exactly the display pixel's centre.
TEST(Patterns, NoiseFreeGrayCodeRecoversTheExactMeanOfSinglePixelRows) {
    const CsrMatrix T = single_pixel_rows();
    const SensorModel s = noise_free();
    const Measurements y = simulate(T, gray_code_block(kP, kQ), s, 0, 1);
    const FeatureImages f = decode_mean_position(y, nullptr, kQ, kP, kDisplay, 0, 16, s, 5);
    for (int p = 0; p < kP; ++p)
        for (int q = 0; q < kQ; ++q) {
            const std::size_t k = static_cast<std::size_t>(p * kQ + q);
            EXPECT_NEAR(f.channel("MeanX")[k], column_x(q), tol::decoded_position(kDisplay.width, std::fabs(column_x(q))))
                << p << ", " << q;
            EXPECT_NEAR(f.channel("MeanY")[k], row_y(p), tol::decoded_position(kDisplay.height, std::fabs(row_y(p))))
                << p << ", " << q;
        }
}

// With phase shifting (4 steps, period 6 px, gamma 2.2 compensated, 16-bit display): the phase of a
// single-pixel row is 2 pi q / period up to the display's quantisation (Tolerances.h,
// phase_position), unwrapped around the Gray column q itself.
TEST(Patterns, NoiseFreePhaseShiftingRecoversTheExactMeanOfSinglePixelRows) {
    const CsrMatrix T = single_pixel_rows();
    const SensorModel s = noise_free();
    const int steps = 4;
    const double period = 6;
    const Measurements g = simulate(T, gray_code_block(kP, kQ), s, 0, 1);
    const Measurements ph = simulate(T, phase_block(kP, kQ, steps, period, s.display), s, g.K, 1);
    const FeatureImages f = decode_mean_position(g, &ph, kQ, kP, kDisplay, steps, period, s, 5);
    for (int p = 0; p < kP; ++p)
        for (int q = 0; q < kQ; ++q) {
            const std::size_t k = static_cast<std::size_t>(p * kQ + q);
            const double tx = tol::phase_position(period, s.display.gamma, s.display.bits, kDisplay.width / kQ,
                                                  kDisplay.width, std::fabs(column_x(q)));
            const double ty = tol::phase_position(period, s.display.gamma, s.display.bits, kDisplay.height / kP,
                                                  kDisplay.height, std::fabs(row_y(p)));
            EXPECT_NEAR(f.channel("MeanX")[k], column_x(q), tx) << p << ", " << q;
            EXPECT_NEAR(f.channel("MeanY")[k], row_y(p), ty) << p << ", " << q;
        }
}

// Two equal entries at columns q and q + 2 of one display row: the phase sum is
// t (e^(i a q) + e^(i a (q + 2))) = 2 t cos(a) e^(i a (q + 1)), a = 2 pi / period, so the phase is
// exactly that of column q + 1 (for cos a > 0, i.e. the pair within a quarter period), which is
// the energy-weighted mean; Gray code alone would give one of the two pixels.
TEST(Patterns, PhaseShiftingGivesTheMeanOfATwoPixelRow) {
    std::vector<std::vector<std::pair<int, float>>> rows;
    for (int q = 0; q + 2 < kQ; ++q) rows.push_back({{2 * kQ + q, 0.25f}, {2 * kQ + q + 2, 0.25f}});
    const CsrMatrix T = rows_matrix(rows, kP * kQ);
    const SensorModel s = noise_free();
    const int steps = 5;
    const double period = 12;
    const Measurements g = simulate(T, gray_code_block(kP, kQ), s, 0, 1);
    const Measurements ph = simulate(T, phase_block(kP, kQ, steps, period, s.display), s, g.K, 1);
    const FeatureImages f = decode_mean_position(g, &ph, static_cast<int>(rows.size()), 1, kDisplay, steps, period, s, 5);
    for (int q = 0; q + 2 < kQ; ++q) {
        const double tx = tol::phase_position(period, s.display.gamma, s.display.bits, kDisplay.width / kQ,
                                              kDisplay.width, std::fabs(column_x(q + 1)));
        EXPECT_NEAR(f.channel("MeanX")[static_cast<std::size_t>(q)], column_x(q + 1), tx) << q;
        EXPECT_NEAR(f.channel("MeanY")[static_cast<std::size_t>(q)], row_y(2),
                    tol::phase_position(period, s.display.gamma, s.display.bits, kDisplay.height / kP, kDisplay.height,
                                        std::fabs(row_y(2))));
    }
}

TEST(Patterns, EmptyRowsHaveNoMeanPosition) {
    const CsrMatrix T = rows_matrix({{}, {{3, 0.5f}}}, kP * kQ);
    const SensorModel s = noise_free();
    const Measurements y = simulate(T, gray_code_block(kP, kQ), s, 0, 1);
    const FeatureImages f = decode_mean_position(y, nullptr, 2, 1, kDisplay, 0, 16, s, 5);
    EXPECT_TRUE(std::isnan(f.channel("MeanX")[0]));
    EXPECT_FALSE(std::isnan(f.channel("MeanX")[1]));
}

// Line scans (w = 1): column stripe q's marginal is sum_p T[k, (p, q)] > 0 exactly where the row
// has an entry in column q, so ScatterColumns = q_max - q_min and ScatterRows = p_max - p_min
// exactly; ScatterWidth's bound is (p_max - p_min) Q + (q_max - q_min), equal to the true width
// l_last - l_first when the entries span one display row or the first sits at (p_min, q_min) and
// the last at (p_max, q_max). Wider stripes give the extent in stripes, times w.
TEST(Patterns, LineScansRecoverTheExactRowAndColumnExtents) {
    const std::vector<std::vector<std::pair<int, float>>> rows = {
        {{1 * kQ + 2, 0.2f}, {1 * kQ + 7, 0.1f}},                     // one display row: rows 0, columns 5, width 5
        {{0 * kQ + 1, 0.3f}, {3 * kQ + 4, 0.1f}, {4 * kQ + 9, 0.05f}},  // (0,1) .. (4,9): width 4 Q + 8
        {{2 * kQ + 6, 0.6f}},                                         // a single pixel: all 0
        {{0 * kQ + 12, 0.1f}, {4 * kQ + 0, 0.1f}}};                  // rows 4, columns 12, width 4 Q - 12
    const CsrMatrix T = rows_matrix(rows, kP * kQ);
    const SensorModel s = noise_free();
    const Measurements y = simulate(T, stripe_block(kP, kQ, 1), s, 0, 1);
    const FeatureImages f = decode_stripes(y, 4, 1, kDisplay, 1, s, 5);
    const std::vector<float> want_rows = {0, 4, 0, 4}, want_cols = {5, 8, 0, 12};
    const std::vector<float> want_bound = {5, 4 * kQ + 8, 0, 4 * kQ + 12};
    for (std::size_t k = 0; k < 4; ++k) {
        EXPECT_EQ(f.channel("ScatterRows")[k], want_rows[k]) << k;
        EXPECT_EQ(f.channel("ScatterColumns")[k], want_cols[k]) << k;
        EXPECT_EQ(f.channel("ScatterWidth")[k], want_bound[k]) << k;
    }
    // Stripes 2 wide: row 1's columns 2 and 7 fall in stripes 1 and 3: extent 2 stripes = 4 px
    // (the truth, 5, lies within w - 1 = 1 of it).
    const FeatureImages f2 = decode_stripes(simulate(T, stripe_block(kP, kQ, 2), s, 0, 1), 4, 1, kDisplay, 2, s, 5);
    EXPECT_EQ(f2.channel("ScatterColumns")[0], 4);
}

TEST(Patterns, PatternCountsFollowTheDisplay) {
    AcquireOptions o;
    o.method = Method::Gray;
    o.patterns = 14;
    EXPECT_EQ(check_patterns(o, kP, kQ), "");
    o.patterns = 20;  // 3 phase steps per axis
    EXPECT_EQ(check_patterns(o, kP, kQ), "");
    o.patterns = 16;  // 1 step per axis: cannot shift phase
    EXPECT_NE(check_patterns(o, kP, kQ).find("method gray needs"), std::string::npos);
    o.method = Method::Stripes;
    o.patterns = kP + kQ;  // a line scan
    EXPECT_EQ(check_patterns(o, kP, kQ), "");
    EXPECT_EQ(stripe_width_for(kP + kQ, kP, kQ), 1);
    o.patterns = 17;  // no stripe width gives 17 for 5 x 13
    EXPECT_NE(check_patterns(o, kP, kQ).find("is not such a count"), std::string::npos);
    o.method = Method::BruteForce;
    o.patterns = kP * kQ;
    EXPECT_EQ(check_patterns(o, kP, kQ), "");
    o.patterns = kP * kQ + 1;
    EXPECT_NE(check_patterns(o, kP, kQ).find("--patterns must be in [1, 65]"), std::string::npos);
}

}  // namespace
