// Row features of T (features/Features.h): hand-built rows with their answers derived next to
// them, a seeded random matrix against a slow direct reference (dense rows, long double), thread
// independence, and the preconditions.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "features/Features.h"
#include "tests/TestSupport.h"
#include "tests/Tolerances.h"
#include "io/CsrMatrix.h"

using namespace ltm;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Entry {
    int p, q;
    float v;
};

// T with one row per camera pixel from (p, q, value) lists (any order; sorted here by l).
CsrMatrix make(int P, int Q, const std::vector<std::vector<Entry>>& rows) {
    CsrMatrix T = CsrMatrix::zeros(static_cast<std::int64_t>(rows.size()), static_cast<std::int64_t>(P) * Q);
    for (std::size_t r = 0; r < rows.size(); ++r) {
        std::map<std::int32_t, float> row;
        for (const Entry& e : rows[r]) row[e.p * Q + e.q] = e.v;
        for (const auto& [l, v] : row) {
            T.indices.push_back(l);
            T.data.push_back(v);
        }
        T.indptr[r + 1] = static_cast<std::int64_t>(T.data.size());
    }
    EXPECT_EQ(T.check(), "");
    return T;
}

DisplayGrid grid(int P, int Q, double W = 0, double H = 0) {
    return DisplayGrid{Q, P, W > 0 ? W : Q, H > 0 ? H : P};  // default: 1 mm pixels
}

FeatureOptions opts(double threshold = 0.0, double fraction = 0.99, int block = 0) {
    FeatureOptions o;
    o.threshold = threshold;
    o.energy_fraction = fraction;
    o.dark_block = block;
    return o;
}

float at(const FeatureImages& f, const std::string& name, std::size_t k = 0) { return f.channel(name)[k]; }

void expect_near_exact(const FeatureImages& f, const std::string& name, double exact, std::size_t k = 0) {
    EXPECT_NEAR(at(f, name, k), exact, tol::float_of_exact(exact)) << name << " of row " << k;
}

// Angles of axes are equal modulo 180 degrees.
double angle_difference(double a, double b) {
    const double d = std::fmod(std::fabs(a - b), 180.0);
    return std::min(d, 180.0 - d);
}

std::string error_of(const std::function<void()>& f) { return ltm::test::message_of<std::invalid_argument>(f); }

}  // namespace

TEST(FeatureRows, ChannelNamesAndOrder) {
    const std::vector<std::string> expected = {
        "BrightField",        "DarkField",    "ScatterCount", "ScatterWidth",  "ScatterRows",
        "ScatterColumns",     "ScatterDiameter", "EllipseMajor", "EllipseMinor", "EllipseAngle",
        "RobustScatterCount", "RobustScatterDiameter", "MeanX", "MeanY"};
    const CsrMatrix T = make(3, 4, {{}, {{1, 1, 1.f}}});
    const FeatureImages f = compute_features(T, 2, 1, grid(3, 4), opts());
    ASSERT_EQ(f.channels.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(f.channels[i].first, expected[i]);
    EXPECT_EQ(feature_channel_names(false), expected);
    EXPECT_EQ(f.width, 2);
    EXPECT_EQ(f.height, 1);
    for (const auto& c : f.channels) EXPECT_EQ(c.second.size(), 2u) << c.first;

    std::vector<float> ref = {0.f, 0.f, 0.f, 0.f};
    const FeatureImages g = compute_features(T, 2, 1, grid(3, 4), opts(), &ref);
    auto with = expected;
    with.insert(with.end(), {"DeflectionX", "DeflectionY", "Deflection"});
    ASSERT_EQ(g.channels.size(), with.size());
    for (std::size_t i = 0; i < with.size(); ++i) EXPECT_EQ(g.channels[i].first, with[i]);
    EXPECT_EQ(feature_channel_names(true), with);

    try {
        f.channel("Scatter");
        ADD_FAILURE() << "no exception";
    } catch (const std::out_of_range& e) {
        EXPECT_NE(std::string(e.what()).find("'Scatter'"), std::string::npos) << e.what();
    }
}

// An empty row: no energy, nothing contributes; every feature is 0 and the mean is undefined.
TEST(FeatureRows, EmptyRow) {
    const CsrMatrix T = make(10, 10, {{}});
    std::vector<float> ref = {1.f, 2.f};
    const FeatureImages f = compute_features(T, 1, 1, grid(10, 10), opts(0, 0.99, 4), &ref);
    for (const auto& [name, img] : f.channels) {
        if (name == "MeanX" || name == "MeanY" || name.rfind("Deflection", 0) == 0)
            EXPECT_TRUE(std::isnan(img[0])) << name;
        else
            EXPECT_EQ(img[0], 0.f) << name;
    }
}

// One entry: display 10 columns x 5 rows of 10 mm (100 x 50 mm). Pixel (p, q) = (1, 2) has its
// centre at x = -50 + 2.5 * 10 = -25, y = 25 - 1.5 * 10 = 10 mm. Dark block b = 2: rows
// [5/2 - 1, +2) = [1, 3), columns [10/2 - 1, +2) = [4, 6): q = 2 is outside, so dark = bright.
TEST(FeatureRows, SingleEntry) {
    const CsrMatrix T = make(5, 10, {{{1, 2, 0.5f}}});
    const FeatureImages f = compute_features(T, 1, 1, grid(5, 10, 100, 50), opts(0, 0.99, 2));
    EXPECT_EQ(at(f, "BrightField"), 0.5f);
    EXPECT_EQ(at(f, "DarkField"), 0.5f);
    EXPECT_EQ(at(f, "ScatterCount"), 1.f);
    for (const char* name : {"ScatterWidth", "ScatterRows", "ScatterColumns", "ScatterDiameter", "EllipseMajor",
                             "EllipseMinor", "EllipseAngle", "RobustScatterDiameter"})
        EXPECT_EQ(at(f, name), 0.f) << name;  // exactly: offsets from the first pixel are all 0
    EXPECT_EQ(at(f, "RobustScatterCount"), 1.f);
    expect_near_exact(f, "MeanX", -25.0);
    expect_near_exact(f, "MeanY", 10.0);
}

// Two entries: (p, q) = (2, 3) with 1 and (5, 7) with 3 on a 10 x 10 display of 1 mm pixels.
//  l = 23 and 57: ScatterWidth 34; rows 5 - 2 = 3, columns 7 - 3 = 4; diameter sqrt(9 + 16) = 5.
//  Ellipse: in (x, y) = (q, -p) the points are (3, -2) and (7, -5), 5 apart along (4, -3) / 5; two
//  point masses w1, w2 at distance L have variance w1 w2 L^2 / (w1 + w2)^2 = 3 * 25 / 16 along the
//  line and 0 across it: major 2 sqrt(75 / 16) = sqrt(75) / 2, minor 0, angle atan2(-3, 4).
//  Mean pixel: q = (3 + 21) / 4 = 6, p = (2 + 15) / 4 = 4.25; x = -5 + 6.5 = 1.5, y = 5 - 4.75 = 0.25.
//  Robust at 0.99: 3 < 0.99 * 4, both needed; at 0.75: 3 >= 3, the larger entry alone.
TEST(FeatureRows, TwoEntries) {
    const CsrMatrix T = make(10, 10, {{{2, 3, 1.f}, {5, 7, 3.f}}});
    const FeatureImages f = compute_features(T, 1, 1, grid(10, 10), opts());
    EXPECT_EQ(at(f, "BrightField"), 4.f);
    EXPECT_EQ(at(f, "ScatterCount"), 2.f);
    EXPECT_EQ(at(f, "ScatterWidth"), 34.f);
    EXPECT_EQ(at(f, "ScatterRows"), 3.f);
    EXPECT_EQ(at(f, "ScatterColumns"), 4.f);
    expect_near_exact(f, "ScatterDiameter", 5.0);
    const double lambda = 75.0 / 16.0, E = tol::ellipse_covariance(2, 5.0);
    EXPECT_NEAR(at(f, "EllipseMajor"), 2 * std::sqrt(lambda), tol::ellipse_axis(2 * std::sqrt(lambda), lambda, E));
    EXPECT_NEAR(at(f, "EllipseMinor"), 0.0, tol::ellipse_axis(0.0, 0.0, E));
    EXPECT_LE(angle_difference(at(f, "EllipseAngle"), std::atan2(-3.0, 4.0) * 180 / kPi),
              tol::ellipse_angle_deg(E, lambda));
    EXPECT_EQ(at(f, "RobustScatterCount"), 2.f);
    expect_near_exact(f, "RobustScatterDiameter", 5.0);
    EXPECT_NEAR(at(f, "MeanX"), 1.5, tol::mean_position(10, 1.5));
    EXPECT_NEAR(at(f, "MeanY"), 0.25, tol::mean_position(10, 0.25));

    const FeatureImages g = compute_features(T, 1, 1, grid(10, 10), opts(0, 0.75));
    EXPECT_EQ(at(g, "RobustScatterCount"), 1.f);
    EXPECT_EQ(at(g, "RobustScatterDiameter"), 0.f);
}

// A 3 x 3 cluster of 1s at rows and columns 9..11 and one far, tiny entry 1e-3 at (40, 45) on a
// 50 x 50 display (the "white dot" of a rare far-off path).
//  ScatterCount 10; ScatterWidth (40 * 50 + 45) - (9 * 50 + 9) = 2045 - 459 = 1586; rows 31,
//  columns 36; diameter from (9, 9) to (40, 45): sqrt(31^2 + 36^2) = sqrt(2257) ~ 47.5.
//  Robust at 0.99: total 9.001, target 8.91099; the nine 1s reach 9 >= target, eight only 8:
//  count 9, diameter the cluster's diagonal sqrt(2^2 + 2^2) = sqrt(8). At fraction 1: all 10.
TEST(FeatureRows, FarTinyEntryMovesWidthNotRobust) {
    std::vector<Entry> row;
    for (int p = 9; p <= 11; ++p)
        for (int q = 9; q <= 11; ++q) row.push_back({p, q, 1.f});
    const CsrMatrix cluster = make(50, 50, {row});
    row.push_back({40, 45, 1e-3f});
    const CsrMatrix T = make(50, 50, {row});

    const FeatureImages c = compute_features(cluster, 1, 1, grid(50, 50), opts());
    EXPECT_EQ(at(c, "ScatterWidth"), 2 * 50 + 2);
    expect_near_exact(c, "ScatterDiameter", std::sqrt(8.0));

    const FeatureImages f = compute_features(T, 1, 1, grid(50, 50), opts());
    EXPECT_EQ(at(f, "ScatterCount"), 10.f);
    EXPECT_EQ(at(f, "ScatterWidth"), 1586.f);
    EXPECT_EQ(at(f, "ScatterRows"), 31.f);
    EXPECT_EQ(at(f, "ScatterColumns"), 36.f);
    expect_near_exact(f, "ScatterDiameter", std::sqrt(2257.0));
    EXPECT_EQ(at(f, "RobustScatterCount"), 9.f);
    expect_near_exact(f, "RobustScatterDiameter", std::sqrt(8.0));
    EXPECT_EQ(at(f, "RobustScatterCount"), at(c, "ScatterCount"));
    EXPECT_EQ(at(f, "RobustScatterDiameter"), at(c, "ScatterDiameter"));

    const FeatureImages all = compute_features(T, 1, 1, grid(50, 50), opts(0, 1.0));
    EXPECT_EQ(at(all, "RobustScatterCount"), 10.f);
    EXPECT_EQ(at(all, "RobustScatterDiameter"), at(f, "ScatterDiameter"));
}

// Threshold: values 1/16, 1/8, 1/2, 1/8 (exact in float and double, so "at the threshold" is
// exact) at (0, 0), (0, 5), (3, 3), (6, 6). With threshold 1/8 only 1/2 is > 1/8 (the two 1/8s
// are not): one contributing entry, at (3, 3). BrightField sums every stored entry whatever the
// threshold: 13/16. With threshold 0.04 all four count: l from 0 to 66.
// Threshold 0 keeps values > 0: explicit zeros and negative values never count.
TEST(FeatureRows, Threshold) {
    const CsrMatrix T = make(10, 10, {{{0, 0, 0.0625f}, {0, 5, 0.125f}, {3, 3, 0.5f}, {6, 6, 0.125f}}});
    const FeatureImages f = compute_features(T, 1, 1, grid(10, 10), opts(0.125));
    EXPECT_EQ(at(f, "BrightField"), 0.8125f);
    EXPECT_EQ(at(f, "ScatterCount"), 1.f);
    EXPECT_EQ(at(f, "ScatterWidth"), 0.f);
    EXPECT_EQ(at(f, "ScatterDiameter"), 0.f);
    EXPECT_EQ(at(f, "EllipseMajor"), 0.f);
    EXPECT_EQ(at(f, "RobustScatterCount"), 1.f);
    expect_near_exact(f, "MeanX", -5 + 3.5);
    expect_near_exact(f, "MeanY", 5 - 3.5);

    const FeatureImages g = compute_features(T, 1, 1, grid(10, 10), opts(0.04));
    EXPECT_EQ(at(g, "ScatterCount"), 4.f);
    EXPECT_EQ(at(g, "ScatterWidth"), 66.f);
    EXPECT_EQ(at(g, "ScatterRows"), 6.f);
    EXPECT_EQ(at(g, "ScatterColumns"), 6.f);
    expect_near_exact(g, "ScatterDiameter", std::sqrt(72.0));

    const CsrMatrix Z = make(10, 10, {{{0, 0, 0.f}, {2, 2, -0.5f}, {4, 1, 0.25f}, {9, 9, 0.f}}});
    const FeatureImages z = compute_features(Z, 1, 1, grid(10, 10), opts());
    EXPECT_EQ(at(z, "BrightField"), -0.25f);
    EXPECT_EQ(at(z, "ScatterCount"), 1.f);
    EXPECT_EQ(at(z, "ScatterWidth"), 0.f);
    expect_near_exact(z, "MeanX", -5 + 1.5);
}

// Second-moment ellipses of 4 equal weights on the corners of a rectangle with perpendicular
// integer sides u and v: the corners are mean +- u/2 +- v/2, so the covariance is
// (1/4) sum (+-u/2 +- v/2)(...)^T = (u u^T + v v^T) / 4 (cross terms cancel), with eigenvalues
// |u|^2 / 4 along u and |v|^2 / 4 along v. (x, y) = (q, -p): a point (x, y) from the origin
// pixel (p0, q0) is pixel (p0 - y, q0 + x).
TEST(FeatureRows, EllipseOfRotatedRectangle) {
    struct Case {
        int ux, uy, vx, vy;
        double major, minor, angle;
    };
    // u = (4, 2), v = (-1, 2): u.v = 0, |u|^2 = 20, |v|^2 = 5: major 2 sqrt(5), minor 2 sqrt(5/4),
    // along u: atan(2 / 4) = 26.565 degrees. Mirrored (u = (4, -2), v = (1, 2)): -26.565.
    // u = (0, 3), v = (1, 0): vertical major axis: +90 (never -90), 2 sqrt(9/4) = 3 and 1.
    // u = (2, 0), v = (0, 2): a square: a circle, major = minor = 2, angle 0 by convention.
    const double a = std::atan(0.5) * 180 / kPi;
    const std::vector<Case> cases = {{4, 2, -1, 2, 2 * std::sqrt(5.0), std::sqrt(5.0), a},
                                     {4, -2, 1, 2, 2 * std::sqrt(5.0), std::sqrt(5.0), -a},
                                     {0, 3, 1, 0, 3.0, 1.0, 90.0},
                                     {2, 0, 0, 2, 2.0, 2.0, 0.0}};
    for (const Case& c : cases) {
        const int p0 = 10, q0 = 10;
        std::vector<Entry> row;
        for (int s = 0; s < 2; ++s)
            for (int t = 0; t < 2; ++t) {
                const int x = s * c.ux + t * c.vx, y = s * c.uy + t * c.vy;
                row.push_back({p0 - y, q0 + x, 0.25f});
            }
        const FeatureImages f = compute_features(make(20, 20, {row}), 1, 1, grid(20, 20), opts());
        const double D = at(f, "ScatterDiameter");
        const double E = tol::ellipse_covariance(4, D);
        const double l1 = c.major * c.major / 4, l2 = c.minor * c.minor / 4;
        EXPECT_NEAR(at(f, "EllipseMajor"), c.major, tol::ellipse_axis(c.major, l1, E)) << c.ux << ' ' << c.uy;
        EXPECT_NEAR(at(f, "EllipseMinor"), c.minor, tol::ellipse_axis(c.minor, l2, E)) << c.ux << ' ' << c.uy;
        if (l1 > l2)
            EXPECT_NEAR(at(f, "EllipseAngle"), c.angle, tol::ellipse_angle_deg(E, l1 - l2)) << c.ux << ' ' << c.uy;
        else
            EXPECT_EQ(at(f, "EllipseAngle"), 0.f);  // exactly isotropic: the convention
        EXPECT_GT(at(f, "EllipseAngle"), -90.f);
        EXPECT_LE(at(f, "EllipseAngle"), 90.f);
    }
}

// DarkField: block b x b at rows [P/2 - b/2, + b), columns [Q/2 - b/2, + b).
//  10 x 10, b = 4: rows and columns 3..6. Inside: (3, 3) = 1, (6, 6) = 2; outside: (2, 3) = 4,
//  (7, 6) = 8, (3, 7) = 16, (6, 2) = 32: dark 60, bright 63.
//  9 x 9, b = 3: rows and columns 3..5 (centred on pixel 4). Inside (4, 4) = 1, (3, 5) = 2;
//  outside (2, 4) = 4, (6, 4) = 8: dark 12, bright 15.
//  6 rows x 10 columns, b = 4: rows 1..4, columns 3..6. Inside (1, 3) = 1, (4, 6) = 2; outside
//  (0, 3) = 4, (5, 6) = 8, (1, 7) = 16, (4, 2) = 32: dark 60.
//  b = 0: nothing dark, dark = bright; b = min(P, Q) = 9 on 9 x 9: everything dark, 0.
TEST(FeatureRows, DarkFieldBlock) {
    const CsrMatrix A = make(10, 10, {{{3, 3, 1}, {6, 6, 2}, {2, 3, 4}, {7, 6, 8}, {3, 7, 16}, {6, 2, 32}}});
    FeatureImages f = compute_features(A, 1, 1, grid(10, 10), opts(0, 0.99, 4));
    EXPECT_EQ(at(f, "BrightField"), 63.f);
    EXPECT_EQ(at(f, "DarkField"), 60.f);

    const CsrMatrix B = make(9, 9, {{{4, 4, 1}, {3, 5, 2}, {2, 4, 4}, {6, 4, 8}}});
    f = compute_features(B, 1, 1, grid(9, 9), opts(0, 0.99, 3));
    EXPECT_EQ(at(f, "BrightField"), 15.f);
    EXPECT_EQ(at(f, "DarkField"), 12.f);
    f = compute_features(B, 1, 1, grid(9, 9), opts(0, 0.99, 0));
    EXPECT_EQ(at(f, "DarkField"), 15.f);
    f = compute_features(B, 1, 1, grid(9, 9), opts(0, 0.99, 9));
    EXPECT_EQ(at(f, "DarkField"), 0.f);

    const CsrMatrix C = make(6, 10, {{{1, 3, 1}, {4, 6, 2}, {0, 3, 4}, {5, 6, 8}, {1, 7, 16}, {4, 2, 32}}});
    f = compute_features(C, 1, 1, grid(6, 10), opts(0, 0.99, 4));
    EXPECT_EQ(at(f, "DarkField"), 60.f);
}

// BrightField is the row sum, T 1; apply_pattern with all ones gives the same sums in double.
// Rows of a 2 x 2 camera (k = m N + n) on a 4 x 5 display.
TEST(FeatureRows, BrightFieldIsRowSum) {
    const CsrMatrix T = make(4, 5, {{{0, 0, 0.25f}, {3, 4, 0.5f}},
                                    {},
                                    {{1, 1, 0.125f}, {1, 2, 0.125f}, {2, 2, 1.0f}},
                                    {{2, 0, 3.0f}}});
    const FeatureImages f = compute_features(T, 2, 2, grid(4, 5), opts(0, 0.99, 2));
    const std::vector<float> sums = {0.75f, 0.f, 1.25f, 3.f};
    const std::vector<double> y = apply_pattern(T, std::vector<float>(20, 1.f));
    ASSERT_EQ(y.size(), 4u);
    for (std::size_t k = 0; k < 4; ++k) {
        EXPECT_EQ(at(f, "BrightField", k), sums[k]) << k;
        EXPECT_EQ(y[k], sums[k]) << k;
    }
    // A pattern lighting column q = 2 only: rows 2 (0.125 at (1, 2) and 1 at (2, 2)) and nothing else.
    std::vector<float> x(20, 0.f);
    for (int p = 0; p < 4; ++p) x[p * 5 + 2] = 1.f;
    const std::vector<double> z = apply_pattern(T, x);
    EXPECT_EQ(z, (std::vector<double>{0, 0, 1.125, 0}));
}

// Deflection: MeanX/Y minus the reference (mm) and its length. Display 10 x 10 of 1 mm.
//  row 0: (p, q) = (2, 7): mean (-5 + 7.5, 5 - 2.5) = (2.5, 2.5); reference (1, -1.5): (1.5, 4), 4.272.
//  row 1: same entry, reference NaN in y: all three NaN.
//  row 2: empty: NaN whatever the reference.
TEST(FeatureRows, DeflectionAgainstReference) {
    const CsrMatrix T = make(10, 10, {{{2, 7, 0.5f}}, {{2, 7, 0.5f}}, {}});
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<float> ref = {1.f, -1.5f, 0.f, nan, 0.f, 0.f};
    const FeatureImages f = compute_features(T, 3, 1, grid(10, 10), opts(), &ref);
    EXPECT_NEAR(at(f, "DeflectionX", 0), 1.5, tol::mean_position(10, 1.5));
    EXPECT_NEAR(at(f, "DeflectionY", 0), 4.0, tol::mean_position(10, 4.0));
    EXPECT_NEAR(at(f, "Deflection", 0), std::hypot(1.5, 4.0), tol::mean_position(10, 4.3));
    for (std::size_t k : {1u, 2u})
        for (const char* name : {"DeflectionX", "DeflectionY", "Deflection"})
            EXPECT_TRUE(std::isnan(at(f, name, k))) << name << ' ' << k;
    EXPECT_FALSE(std::isnan(at(f, "MeanY", 1)));
    // add_deflection on the features without a reference gives the same bits.
    FeatureImages g = compute_features(T, 3, 1, grid(10, 10), opts());
    add_deflection(g, ref);
    for (const char* name : {"DeflectionX", "DeflectionY", "Deflection"})
        for (std::size_t k = 0; k < 3; ++k) {
            const float a = at(f, name, k), b = at(g, name, k);
            EXPECT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << name << ' ' << k;
        }
    EXPECT_THROW(add_deflection(g, ref), std::invalid_argument);  // already there
}

// A row whose means are its own reference has a deflection of exactly 0 (not a float rounding
// of the double mean): the deflection map of a defect-free region is noise-free by construction.
TEST(FeatureRows, ARowAgainstItsOwnMeansHasZeroDeflection) {
    const CsrMatrix T = make(10, 10, {{{2, 7, 0.3f}, {3, 1, 0.1f}, {9, 9, 0.05f}}});
    const FeatureImages f0 = compute_features(T, 1, 1, grid(10, 10), opts());
    const std::vector<float> ref = {f0.channel("MeanX")[0], f0.channel("MeanY")[0]};
    const FeatureImages f = compute_features(T, 1, 1, grid(10, 10), opts(), &ref);
    EXPECT_EQ(at(f, "DeflectionX", 0), 0.0f);
    EXPECT_EQ(at(f, "DeflectionY", 0), 0.0f);
    EXPECT_EQ(at(f, "Deflection", 0), 0.0f);
}

// ---- a seeded random matrix against a direct reference ----

namespace {

// Deterministic uniform doubles in [0, 1) from a 64-bit Mersenne twister (the standard fixes its
// output sequence; the library distributions are not fixed across implementations).
struct Uniform {
    std::mt19937_64 g;
    explicit Uniform(std::uint64_t seed) : g(seed) {}
    double operator()() { return static_cast<double>(g() >> 11) * 0x1p-53; }
    int below(int n) { return static_cast<int>((*this)() * n); }
};

// A random row of one of several kinds: empty, single, clusters, a cluster with far tiny entries,
// scattered, dense, collinear; values include explicit zeros, negatives, ties and values at the
// threshold 0.25 used below.
std::vector<Entry> random_row(Uniform& U, int P, int Q, int kind) {
    auto value = [&]() -> float {
        const double r = U();
        if (r < 0.05) return 0.f;
        if (r < 0.08) return -static_cast<float>(U());
        if (r < 0.12) return 0.25f;
        if (r < 0.30) return static_cast<float>(U.below(8) + 1) / 8.f;  // ties
        return static_cast<float>(U());
    };
    std::vector<Entry> row;
    switch (kind) {
    case 0: break;
    case 1: row.push_back({U.below(P), U.below(Q), static_cast<float>(0.1 + U())}); break;
    case 2:
    case 3: {
        const int pc = U.below(P), qc = U.below(Q), n = 5 + U.below(30);
        for (int i = 0; i < n; ++i)
            row.push_back({std::clamp(pc + U.below(7) - 3, 0, P - 1), std::clamp(qc + U.below(7) - 3, 0, Q - 1), value()});
        if (kind == 3)
            for (int i = 0, m = 1 + U.below(3); i < m; ++i) row.push_back({U.below(P), U.below(Q), 1e-3f * static_cast<float>(U())});
        break;
    }
    case 4:
        for (int i = 0, n = 10 + U.below(60); i < n; ++i) row.push_back({U.below(P), U.below(Q), value()});
        break;
    case 5:
        for (int p = 0; p < P; ++p)
            for (int q = 0; q < Q; ++q)
                if (U() < 0.9) row.push_back({p, q, value()});
        break;
    default: {  // collinear: a line of direction (dp, dq) through a random start
        const int dp = U.below(3) - 1, dq = dp == 0 ? 1 : U.below(3) - 1;
        int p = U.below(P), q = U.below(Q);
        for (int i = 0; i < 12 && p >= 0 && p < P && q >= 0 && q < Q; ++i, p += dp, q += dq)
            if (U() < 0.8) row.push_back({p, q, value()});
    }
    }
    return row;  // duplicates collapse in make (the last value wins)
}

struct Reference {
    std::map<std::string, std::vector<double>> value;
    std::vector<double> lambda1, lambda2, n, diameter, abs_sum, abs_sum_dark;
};

// The features by their definitions, on dense rows in long double.
Reference reference_features(const CsrMatrix& T, int N, int M, const DisplayGrid& d, const FeatureOptions& o,
                             const std::vector<float>* ref) {
    const int P = d.P, Q = d.Q;
    const int b = o.dark_block, p0 = P / 2 - b / 2, q0 = Q / 2 - b / 2;
    Reference R;
    const std::size_t K = static_cast<std::size_t>(N) * M;
    for (const auto& name : feature_channel_names(ref != nullptr)) R.value[name].assign(K, 0.0);
    R.lambda1.assign(K, 0);
    R.lambda2.assign(K, 0);
    R.n.assign(K, 0);
    R.diameter.assign(K, 0);
    R.abs_sum.assign(K, 0);
    R.abs_sum_dark.assign(K, 0);
    std::vector<double> dense(static_cast<std::size_t>(P) * Q);
    for (std::size_t k = 0; k < K; ++k) {
        std::fill(dense.begin(), dense.end(), 0.0);
        for (auto i = T.indptr[k]; i < T.indptr[k + 1]; ++i) dense[T.indices[i]] = T.data[i];
        auto set = [&](const char* name, double v) { R.value[name][k] = v; };
        long double bright = 0, dark = 0;
        std::vector<int> S;  // contributing columns
        for (int l = 0; l < P * Q; ++l) {
            const int p = l / Q, q = l % Q;
            const bool in = p >= p0 && p < p0 + b && q >= q0 && q < q0 + b;
            bright += dense[l];
            R.abs_sum[k] += std::fabs(dense[l]);
            if (!in) {
                dark += dense[l];
                R.abs_sum_dark[k] += std::fabs(dense[l]);
            }
            if (dense[l] > o.threshold) S.push_back(l);
        }
        set("BrightField", static_cast<double>(bright));
        set("DarkField", static_cast<double>(dark));
        const double nan = std::numeric_limits<double>::quiet_NaN();
        R.n[k] = static_cast<double>(S.size());
        auto diameter_of = [&](const std::vector<int>& ls) {
            long double best = 0;
            for (std::size_t i = 0; i < ls.size(); ++i)
                for (std::size_t j = i + 1; j < ls.size(); ++j) {
                    const long double dp = ls[i] / Q - ls[j] / Q, dq = ls[i] % Q - ls[j] % Q;
                    best = std::max(best, std::sqrt(dp * dp + dq * dq));
                }
            return static_cast<double>(best);
        };
        if (S.empty()) {
            set("MeanX", nan);
            set("MeanY", nan);
        } else {
            set("ScatterCount", static_cast<double>(S.size()));
            set("ScatterWidth", S.back() - S.front());
            int pmin = P, pmax = -1, qmin = Q, qmax = -1;
            for (int l : S) {
                pmin = std::min(pmin, l / Q);
                pmax = std::max(pmax, l / Q);
                qmin = std::min(qmin, l % Q);
                qmax = std::max(qmax, l % Q);
            }
            set("ScatterRows", pmax - pmin);
            set("ScatterColumns", qmax - qmin);
            R.diameter[k] = diameter_of(S);
            set("ScatterDiameter", R.diameter[k]);

            // Ellipse at pixel centres (q + 0.5, -(p + 0.5)); eigenvectors by the rotation that
            // diagonalises the covariance, tan 2 theta = 2 b / (a - c).
            long double W = 0, mx = 0, my = 0, mmx = 0, mmy = 0;
            for (int l : S) {
                const long double w = dense[l], x = l % Q + 0.5L, y = -(l / Q + 0.5L);
                W += w;
                mx += w * x;
                my += w * y;
                mmx += w * (-d.width / 2 + (l % Q + 0.5L) * d.width / Q);
                mmy += w * (d.height / 2 - (l / Q + 0.5L) * d.height / P);
            }
            mx /= W;
            my /= W;
            long double a = 0, bb = 0, c = 0;
            for (int l : S) {
                const long double w = dense[l], x = l % Q + 0.5L - mx, y = -(l / Q + 0.5L) - my;
                a += w * x * x;
                bb += w * x * y;
                c += w * y * y;
            }
            a /= W;
            bb /= W;
            c /= W;
            const long double th = 0.5L * std::atan2(2 * bb, a - c), cs = std::cos(th), sn = std::sin(th);
            const long double l1 = a * cs * cs + 2 * bb * sn * cs + c * sn * sn;
            const long double l2 = a * sn * sn - 2 * bb * sn * cs + c * cs * cs;
            R.lambda1[k] = static_cast<double>(l1);
            R.lambda2[k] = static_cast<double>(std::max(l2, 0.0L));
            set("EllipseMajor", 2 * std::sqrt(R.lambda1[k]));
            set("EllipseMinor", 2 * std::sqrt(R.lambda2[k]));
            double deg = static_cast<double>(th * 180 / kPi);
            if (deg <= -90) deg += 180;
            set("EllipseAngle", deg);
            set("MeanX", static_cast<double>(mmx / W));
            set("MeanY", static_cast<double>(mmy / W));

            // Robust: the definition, in double as specified.
            std::vector<int> order = S;
            std::sort(order.begin(), order.end(), [&](int x, int y) {
                return dense[x] > dense[y] || (dense[x] == dense[y] && x < y);
            });
            double total = 0;
            for (int l : order) total += dense[l];
            std::vector<int> kept;
            double cum = 0;
            for (int l : order) {
                kept.push_back(l);
                cum += dense[l];
                if (cum >= o.energy_fraction * total) break;
            }
            set("RobustScatterCount", static_cast<double>(kept.size()));
            set("RobustScatterDiameter", diameter_of(kept));
        }
        if (ref) {
            const double dx = R.value["MeanX"][k] - (*ref)[2 * k], dy = R.value["MeanY"][k] - (*ref)[2 * k + 1];
            const bool bad = std::isnan(dx) || std::isnan(dy);
            set("DeflectionX", bad ? nan : dx);
            set("DeflectionY", bad ? nan : dy);
            set("Deflection", bad ? nan : std::sqrt(dx * dx + dy * dy));
        }
    }
    return R;
}

void compare_with_reference(const FeatureImages& f, const Reference& R, const DisplayGrid& d) {
    const double extent = std::max(d.width, d.height);
    for (const auto& [name, img] : f.channels) {
        const auto& want = R.value.at(name);
        ASSERT_EQ(img.size(), want.size()) << name;
        for (std::size_t k = 0; k < img.size(); ++k) {
            const double got = img[k], w = want[k];
            const std::string where = name + " of row " + std::to_string(k);
            if (std::isnan(w) || std::isnan(got)) {
                EXPECT_TRUE(std::isnan(w) && std::isnan(got)) << where << ": " << got << " vs " << w;
                continue;
            }
            const double E = tol::ellipse_covariance(static_cast<long>(R.n[k]), R.diameter[k]);
            if (name == "BrightField") {
                EXPECT_NEAR(got, w, tol::float_sum(R.abs_sum[k])) << where;
            } else if (name == "DarkField") {
                EXPECT_NEAR(got, w, tol::float_sum(R.abs_sum_dark[k])) << where;
            } else if (name == "ScatterDiameter" || name == "RobustScatterDiameter") {
                EXPECT_NEAR(got, w, tol::float_of_exact(w)) << where;
            } else if (name == "EllipseMajor") {
                EXPECT_NEAR(got, w, tol::ellipse_axis(w, R.lambda1[k], E)) << where;
            } else if (name == "EllipseMinor") {
                EXPECT_NEAR(got, w, tol::ellipse_axis(w, R.lambda2[k], E)) << where;
            } else if (name == "EllipseAngle") {
                EXPECT_GT(got, -90.0) << where;
                EXPECT_LE(got, 90.0) << where;
                EXPECT_LE(angle_difference(got, w), tol::ellipse_angle_deg(E, R.lambda1[k] - R.lambda2[k]))
                    << where << ": " << got << " vs " << w;
            } else if (name.rfind("Mean", 0) == 0 || name.rfind("Deflection", 0) == 0) {
                EXPECT_NEAR(got, w, tol::mean_position(extent, std::fabs(w))) << where;
            } else {  // counts and index extents: exact integers
                EXPECT_EQ(got, w) << where;
            }
        }
    }
}

struct RandomCase {
    int N = 7, M = 6, P = 17, Q = 23;
    DisplayGrid display{23, 17, 46.0, 25.5};
    CsrMatrix T;
    std::vector<float> reference;
};

RandomCase random_case(std::uint64_t seed) {
    RandomCase c;
    Uniform U(seed);
    std::vector<std::vector<Entry>> rows;
    for (int k = 0; k < c.N * c.M; ++k) rows.push_back(random_row(U, c.P, c.Q, k % 7));
    c.T = make(c.P, c.Q, rows);
    for (int k = 0; k < c.N * c.M; ++k) {
        c.reference.push_back(U() < 0.1 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(20 * U() - 10));
        c.reference.push_back(static_cast<float>(10 * U() - 5));
    }
    return c;
}

}  // namespace

TEST(FeatureRows, RandomMatrixAgainstDirectReference) {
    const std::vector<FeatureOptions> options = {opts(0.0, 0.99, 7), opts(0.25, 0.5, 0), opts(0.0, 1.0, 17),
                                                 opts(0.5, 0.9, 1)};
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        const RandomCase c = random_case(seed);
        for (const FeatureOptions& o : options) {
            SCOPED_TRACE("seed " + std::to_string(seed) + ", threshold " + std::to_string(o.threshold) +
                         ", fraction " + std::to_string(o.energy_fraction) + ", block " + std::to_string(o.dark_block));
            for (const std::vector<float>* ref : {static_cast<const std::vector<float>*>(nullptr), &c.reference}) {
                const FeatureImages f = compute_features(c.T, c.N, c.M, c.display, o, ref);
                compare_with_reference(f, reference_features(c.T, c.N, c.M, c.display, o, ref), c.display);
            }
        }
    }
}

// Each value depends on its own row only: bit-identical images whatever the number of threads.
TEST(FeatureRows, IndependentOfThreadCount) {
    // A taller random matrix so that the rows are split into several parallel chunks.
    RandomCase c;
    c.N = 40;
    c.M = 30;
    Uniform U(7);
    std::vector<std::vector<Entry>> rows;
    for (int k = 0; k < c.N * c.M; ++k) rows.push_back(random_row(U, c.P, c.Q, k % 7));
    c.T = make(c.P, c.Q, rows);
    for (int k = 0; k < 2 * c.N * c.M; ++k) c.reference.push_back(static_cast<float>(U()));
    auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
        return compute_features(c.T, c.N, c.M, c.display, opts(0.0, 0.9, 5), &c.reference);
    };
    const FeatureImages one = run(1), four = run(4);
    ASSERT_EQ(one.channels.size(), four.channels.size());
    for (std::size_t i = 0; i < one.channels.size(); ++i) {
        const auto& a = one.channels[i].second;
        const auto& b = four.channels[i].second;
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << one.channels[i].first;
    }
}

// mean_positions gives a subset of rows (in any order, repeated, empty ones among them) exactly
// the MeanX and MeanY that compute_features gives them (which RandomMatrixAgainstDirectReference
// checks against the direct reference), bit for bit, NaN included; its preconditions are named.
TEST(FeatureRows, MeanPositionsOfSomeRowsAreComputeFeaturesMeans) {
    for (std::uint64_t seed : {4u, 5u}) {
        const RandomCase c = random_case(seed);
        std::vector<long> rows;
        for (long k = c.N * c.M - 1; k >= 0; k -= 3) rows.push_back(k);
        rows.push_back(0);
        rows.push_back(0);
        for (const double threshold : {0.0, 0.25, 0.5}) {
            SCOPED_TRACE("seed " + std::to_string(seed) + ", threshold " + std::to_string(threshold));
            const FeatureImages f = compute_features(c.T, c.N, c.M, c.display, opts(threshold));
            const std::vector<float> m = mean_positions(c.T, rows, c.display, threshold);
            ASSERT_EQ(m.size(), 2 * rows.size());
            int empty = 0;
            for (std::size_t j = 0; j < rows.size(); ++j) {
                const auto k = static_cast<std::size_t>(rows[j]);
                EXPECT_EQ(std::memcmp(&m[2 * j], &f.channel("MeanX")[k], sizeof(float)), 0) << "row " << k;
                EXPECT_EQ(std::memcmp(&m[2 * j + 1], &f.channel("MeanY")[k], sizeof(float)), 0) << "row " << k;
                empty += std::isnan(m[2 * j]) ? 1 : 0;
            }
            EXPECT_GT(empty, 0) << "the case should hold rows with nothing above the threshold";
            EXPECT_LT(empty, static_cast<int>(rows.size()));
        }
    }
    const CsrMatrix T = make(4, 5, {{{0, 0, 1.f}}, {}});
    EXPECT_TRUE(mean_positions(T, {}, grid(4, 5), 0.0).empty());
    const auto has = [](const std::string& msg, const std::string& part) { return msg.find(part) != std::string::npos; };
    EXPECT_TRUE(has(error_of([&] { mean_positions(T, {2}, grid(4, 5), 0.0); }), "row 2 is not a row of T (2 rows)"));
    EXPECT_TRUE(has(error_of([&] { mean_positions(T, {-1}, grid(4, 5), 0.0); }), "row -1 is not a row of T"));
    EXPECT_TRUE(has(error_of([&] { mean_positions(T, {0}, grid(4, 4), 0.0); }),
                    "T has 20 columns but the display has P * Q = 16 pixels"));
    EXPECT_TRUE(has(error_of([&] { mean_positions(T, {0}, grid(4, 5), -1.0); }), "threshold must be finite and >= 0"));
    EXPECT_TRUE(has(error_of([&] { mean_positions(T, {0}, DisplayGrid{5, 4, 0.0, 4.0}, 0.0); }), "the display must"));
}

TEST(FeatureRows, Preconditions) {
    const CsrMatrix T = make(4, 5, {{{0, 0, 1.f}}, {}});  // 2 rows, 20 columns
    const DisplayGrid d = grid(4, 5);
    auto err = [&](const CsrMatrix& t, int N, int M, const DisplayGrid& g, const FeatureOptions& o,
                   const std::vector<float>* ref = nullptr) {
        return error_of([&] { compute_features(t, N, M, g, o, ref); });
    };
    auto has = [](const std::string& msg, const std::string& part) {
        return msg.find(part) != std::string::npos;
    };
    EXPECT_TRUE(has(err(T, 2, 1, d, opts()), "(no exception)")) << "the valid call must not throw";
    EXPECT_TRUE(has(err(T, 3, 1, d, opts()), "T has 2 rows but the camera has N * M = 3 * 1 = 3"));
    EXPECT_TRUE(has(err(T, 1, 2, grid(4, 4), opts()), "T has 20 columns but the display has P * Q = 4 * 4 = 16"));
    EXPECT_TRUE(has(err(T, 0, 1, d, opts()), "at least one column and one row"));
    EXPECT_TRUE(has(err(T, 2, 1, grid(0, 5), opts()), "the display must have at least one"));
    EXPECT_TRUE(has(err(T, 2, 1, DisplayGrid{5, 4, 0.0, 4.0}, opts()), "display size"));
    EXPECT_TRUE(has(err(T, 2, 1, DisplayGrid{5, 4, 5.0, std::nan("")}, opts()), "display size"));
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(-0.1)), "threshold must be finite and >= 0"));
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(std::nan(""))), "threshold"));
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(std::numeric_limits<double>::infinity())), "threshold"));
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(0, 0.0)), "energy_fraction must lie in (0, 1]"));
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(0, 1.5)), "energy_fraction"));
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(0, std::nan(""))), "energy_fraction"));
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(0, 0.99, -1)), "dark_block must lie in [0, min(P, Q)] = [0, 4]"));
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(0, 0.99, 5)), "dark_block"));
    EXPECT_TRUE(has(err(T, 2, 1, d, FeatureOptions{}), "dark_block"));  // the default 60 > 4
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(0, 0.99, 4)), "(no exception)"));
    std::vector<float> ref(3);
    EXPECT_TRUE(has(err(T, 2, 1, d, opts(), &ref), "reference_mean has 3 values, expected 2 per camera pixel = 4"));

    CsrMatrix bad = T;
    bad.indices[0] = 20;
    EXPECT_TRUE(has(err(bad, 2, 1, d, opts()), "T is not a valid CSR matrix: column index 20"));
    EXPECT_TRUE(has(error_of([&] { apply_pattern(bad, std::vector<float>(20)); }), "not a valid CSR matrix"));
    EXPECT_TRUE(has(error_of([&] { apply_pattern(T, std::vector<float>(19)); }),
                    "the pattern has 19 values but T has 20 columns"));
}
