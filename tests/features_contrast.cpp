// Numbers for defect images (features/Contrast.h): pixel regions, contrast-to-noise ratio, robust
// false-positive counts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "features/Contrast.h"
#include "tests/Tolerances.h"

using ltm::Region;

namespace {

constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

// Every pixel of a width x height image, its centre tested directly (no bounding box).
std::vector<int> brute_force_ring(int width, int height, double cx, double cy, double r_in, double r_out) {
    std::vector<int> out;
    for (int k = 0; k < width * height; ++k) {
        const int m = k / width, n = k % width;
        const double dx = (n + 0.5) - cx, dy = (m + 0.5) - cy;
        const double d2 = dx * dx + dy * dy;
        if (d2 <= r_out * r_out && (r_in < 0 || d2 > r_in * r_in)) out.push_back(k);
    }
    return out;
}

}  // namespace

// ---- regions ----

TEST(Regions, DiscOfRadiusHalfAroundAPixelCentreIsThatPixel) {
    const int W = 7, H = 5;
    for (int m = 0; m < H; ++m)
        for (int n = 0; n < W; ++n) {
            EXPECT_EQ(ltm::disc_region(W, H, n + 0.5, m + 0.5, 0.5).pixels, std::vector<int>{m * W + n});
            EXPECT_EQ(ltm::disc_region(W, H, n + 0.5, m + 0.5, 0.0).pixels, std::vector<int>{m * W + n});
        }
}

TEST(Regions, XRunsAlongColumnsAndYDownTheRows) {
    // (cx, cy) = (8.5, 1.5): column 8 of row 1 of a 10-wide image, k = 1 * 10 + 8
    EXPECT_EQ(ltm::disc_region(10, 4, 8.5, 1.5, 0.5).pixels, std::vector<int>{18});
    // radius 1 reaches the four edge neighbours (distance exactly 1, inclusive), not the diagonals
    EXPECT_EQ(ltm::disc_region(10, 4, 8.5, 1.5, 1.0).pixels, (std::vector<int>{8, 17, 18, 19, 28}));
    // clipped at the corner: only pixel 0's centre is within 1 of (0, 0)
    EXPECT_EQ(ltm::disc_region(10, 4, 0.0, 0.0, 1.0).pixels, std::vector<int>{0});
    // far outside: empty
    EXPECT_TRUE(ltm::disc_region(10, 4, -50.0, 2.0, 10.0).pixels.empty());
    // a huge radius: everything, in order
    const Region all = ltm::disc_region(10, 4, 5.0, 2.0, 1e9);
    ASSERT_EQ(all.pixels.size(), 40u);
    for (int k = 0; k < 40; ++k) EXPECT_EQ(all.pixels[static_cast<std::size_t>(k)], k);
}

TEST(Regions, AnnulusCountsMatchABruteForceCount) {
    struct Case { double cx, cy, r_in, r_out; };
    const Case cases[] = {
        {50.0, 50.0, 10.0, 20.0},   // centre on a pixel corner: many centres at exactly r
        {50.5, 50.5, 10.0, 20.0},   // centre on a pixel centre
        {12.3, 87.9, 3.7, 25.2},    // off-grid, clipped at two edges
        {0.0, 0.0, 30.0, 60.0},     // the image's corner
        {99.9, 50.0, 5.0, 200.0},   // reaching past every edge
        {33.3, 66.6, 0.0, 0.0},     // nothing (no centre exactly there)
        {40.5, 60.5, 0.0, 7.0},     // r_in = 0 drops only the centre pixel itself
        {70.0, 20.0, 15.0, 15.0},   // r_in = r_out: empty
    };
    const int W = 100, H = 100;
    for (const Case& c : cases) {
        const Region a = ltm::annulus_region(W, H, c.cx, c.cy, c.r_in, c.r_out);
        const std::vector<int> expected = brute_force_ring(W, H, c.cx, c.cy, c.r_in, c.r_out);
        EXPECT_EQ(a.pixels.size(), expected.size()) << c.cx << " " << c.cy << " " << c.r_in << " " << c.r_out;
        EXPECT_EQ(a.pixels, expected);
        // the annulus is the outer disc without the inner one
        const Region d = ltm::subtract(ltm::disc_region(W, H, c.cx, c.cy, c.r_out), ltm::disc_region(W, H, c.cx, c.cy, c.r_in));
        EXPECT_EQ(a.pixels, d.pixels);
        EXPECT_EQ(ltm::disc_region(W, H, c.cx, c.cy, c.r_out).pixels, brute_force_ring(W, H, c.cx, c.cy, -1.0, c.r_out));
    }
    // a known count: centres (i + 1/2, j + 1/2) relative to a pixel corner within radius 1.6:
    // the 4 at distance 0.71 and the 8 at 1.58 (sqrt(0.25 + 2.25))
    EXPECT_EQ(ltm::disc_region(W, H, 50.0, 50.0, 1.6).pixels.size(), 12u);
    EXPECT_EQ(ltm::annulus_region(W, H, 50.0, 50.0, 1.0, 1.6).pixels.size(), 8u);
}

TEST(Regions, SubtractKeepsTheFirstRegionsOrder) {
    const Region a{{9, 3, 7, 1, 5}}, b{{5, 9, 42}};
    EXPECT_EQ(ltm::subtract(a, b).pixels, (std::vector<int>{3, 7, 1}));
    EXPECT_EQ(ltm::subtract(a, Region{}).pixels, a.pixels);
    EXPECT_TRUE(ltm::subtract(Region{}, a).pixels.empty());
}

TEST(Regions, BadArguments) {
    EXPECT_THROW(ltm::disc_region(-1, 4, 0, 0, 1), std::invalid_argument);
    EXPECT_THROW(ltm::disc_region(4, 4, 0, 0, -1), std::invalid_argument);
    EXPECT_THROW(ltm::disc_region(4, 4, std::nan(""), 0, 1), std::invalid_argument);
    EXPECT_THROW(ltm::annulus_region(4, 4, 0, 0, 2, 1), std::invalid_argument);
    EXPECT_THROW(ltm::annulus_region(4, 4, 0, 0, -1, 1), std::invalid_argument);
}

// ---- contrast to noise ----

TEST(ContrastToNoise, SmallImageByHand) {
    // surround 1, 2, 3, 4: mean 2.5, sample variance (2.25 + 0.25 + 0.25 + 2.25) / 3 = 5 / 3;
    // defect 10, 10.5: mean 10.25; CNR = 7.75 / sqrt(5 / 3)
    const std::vector<float> img = {1, 2, 3, 4, 10, 10.5f, kNaNf, 99};
    const Region surround{{0, 1, 2, 3, 6}};  // the NaN pixel is left out
    const Region defect{{4, 5}};
    const ltm::ContrastResult r = ltm::contrast_to_noise(img, defect, surround);
    EXPECT_EQ(r.defect_pixels, 2);
    EXPECT_EQ(r.surround_pixels, 4);
    EXPECT_EQ(r.defect_mean, 10.25);
    EXPECT_EQ(r.surround_mean, 2.5);
    const double std_ref = std::sqrt(5.0 / 3.0), cnr_ref = 7.75 / std_ref;
    EXPECT_NEAR(r.surround_std, std_ref, ltm::tol::contrast_exact() * std_ref);
    EXPECT_NEAR(r.cnr, cnr_ref, ltm::tol::contrast_exact() * cnr_ref);
    // a darker defect has the same CNR (absolute difference)
    const std::vector<float> dark = {11, 12, 13, 14, 3.25f, 3.25f, 0, 0};
    EXPECT_NEAR(ltm::contrast_to_noise(dark, defect, Region{{0, 1, 2, 3}}).cnr, 9.25 / std_ref,
                ltm::tol::contrast_exact() * 9.25 / std_ref);
}

TEST(ContrastToNoise, NoiseFreeSurround) {
    const std::vector<float> img = {1, 1, 1, 2, 2, 1, 1};
    const Region surround{{0, 1, 2}};
    EXPECT_EQ(ltm::contrast_to_noise(img, Region{{3, 4}}, surround).cnr, std::numeric_limits<double>::infinity());
    EXPECT_EQ(ltm::contrast_to_noise(img, Region{{5, 6}}, surround).cnr, 0.0);
    EXPECT_EQ(ltm::contrast_to_noise(img, Region{{5, 6}}, surround).surround_std, 0.0);
}

TEST(ContrastToNoise, ASurroundNeverShowsLessNoiseThanItsResolution) {
    // The dark field of a bubble whose surround all lands on the dark block: exactly 0 in every
    // surround pixel of a render with S = 256 samples per pixel, 0.05 in the defect. One sample is
    // 1/256 of a pixel's light, the step the image resolves: the noise is taken as
    // (1/256) / sqrt 12 = 0.0011276, not 0, and the CNR is 0.05 / 0.0011276 = 44.34, not inf.
    const std::vector<float> img = {0, 0, 0, 0, 0.05f, 0.05f};
    const Region surround{{0, 1, 2, 3}}, defect{{4, 5}};
    const double q = 1.0 / 256;
    const ltm::ContrastResult r = ltm::contrast_to_noise(img, defect, surround, q);
    EXPECT_EQ(r.surround_std, 0.0);
    EXPECT_EQ(r.noise, q / std::sqrt(12.0));
    EXPECT_NEAR(r.cnr, static_cast<double>(0.05f) / (q / std::sqrt(12.0)), ltm::tol::contrast_exact() * 44.34);
    EXPECT_TRUE(std::isfinite(r.cnr));
    // A surround noisier than its resolution keeps its own standard deviation (SmallImageByHand's).
    const std::vector<float> noisy = {1, 2, 3, 4, 10, 10.5f};
    const ltm::ContrastResult n = ltm::contrast_to_noise(noisy, defect, surround, 1.0);
    EXPECT_EQ(n.noise, n.surround_std);
    EXPECT_EQ(n.cnr, ltm::contrast_to_noise(noisy, defect, surround).cnr);
    EXPECT_THROW(ltm::contrast_to_noise(img, defect, surround, -1.0), std::invalid_argument);
    EXPECT_THROW(ltm::contrast_to_noise(img, defect, surround, std::numeric_limits<double>::infinity()),
                 std::invalid_argument);
}

TEST(ContrastToNoise, ResolutionByTheChannelsUnit) {
    ltm::Resolution q;
    q.fraction = 1.0 / 256;
    q.mm = 0.2 / 256;
    q.display_pixels = 8;
    q.moment = 1.0 / 256;
    EXPECT_EQ(q.of("BrightField"), 1.0 / 256);
    EXPECT_EQ(q.of("DarkField"), 1.0 / 256);
    EXPECT_EQ(q.of("Deflection"), 0.2 / 256);
    EXPECT_EQ(q.of("MeanY"), 0.2 / 256);
    EXPECT_EQ(q.of("ScatterRows"), 8.0);
    EXPECT_EQ(q.of("ScatterDiameter"), 8.0);
    EXPECT_EQ(q.of("EllipseMinor"), 1.0 / 256);
    EXPECT_EQ(q.of("EllipseMajor"), 1.0 / 256);
    EXPECT_EQ(q.of("ScatterCount"), 1.0);
    EXPECT_EQ(q.of("ScatterWidth"), 1.0);
    EXPECT_EQ(q.of("EllipseAngle"), 1.0);
    EXPECT_EQ(q.of("NoSuchChannel"), 0.0);
}

TEST(ContrastToNoise, TooFewFinitePixelsOrBadIndices) {
    const std::vector<float> img = {1, 2, 3, kNaNf, std::numeric_limits<float>::infinity()};
    // One defect pixel is enough for its mean; the surround's spread needs two.
    EXPECT_NO_THROW(ltm::contrast_to_noise(img, Region{{0}}, Region{{1, 2}}));
    EXPECT_EQ(ltm::contrast_to_noise(img, Region{{0}}, Region{{1, 2}}).defect_pixels, 1);
    EXPECT_THROW(ltm::contrast_to_noise(img, Region{{3, 4}}, Region{{1, 2}}), std::invalid_argument);
    EXPECT_THROW(ltm::contrast_to_noise(img, Region{{0, 1}}, Region{{2, 3}}), std::invalid_argument);
    EXPECT_THROW(ltm::contrast_to_noise(img, Region{{0, 1}}, Region{}), std::invalid_argument);
    EXPECT_THROW(ltm::contrast_to_noise(img, Region{{0, 5}}, Region{{1, 2}}), std::invalid_argument);
    EXPECT_THROW(ltm::contrast_to_noise(img, Region{{-1, 0}}, Region{{1, 2}}), std::invalid_argument);
    EXPECT_NO_THROW(ltm::contrast_to_noise(img, Region{{0, 1, 3}}, Region{{1, 2, 4}}));
}

TEST(ContrastToNoise, StepInGaussianNoise) {
    // A 128 x 128 image: background 0.3, a disc (radius 20) brighter by step = 0.05, Gaussian
    // noise sigma = 0.02 everywhere (seeded): the true CNR is step / sigma = 2.5. The surround is
    // the annulus 30 - 60 around the same centre. The estimate's standard error to first order
    // (tests/Tolerances.h, cnr_standard_error) is sqrt(1/n_d + 1/n_s + c^2 / (2 (n_s - 1)));
    // with n_d ~ 1257, n_s ~ 8482: ~0.036.
    const int W = 128, H = 128;
    const double background = 0.3, step = 0.05, sigma = 0.02;
    const Region defect = ltm::disc_region(W, H, 64.0, 64.0, 20.0);
    const Region surround = ltm::annulus_region(W, H, 64.0, 64.0, 30.0, 60.0);
    std::vector<float> img(static_cast<std::size_t>(W * H));
    std::mt19937_64 rng(20240611);
    std::normal_distribution<double> noise(0.0, sigma);
    for (auto& v : img) v = static_cast<float>(background + noise(rng));
    for (const int k : defect.pixels) img[static_cast<std::size_t>(k)] += static_cast<float>(step);

    const ltm::ContrastResult r = ltm::contrast_to_noise(img, defect, surround);
    EXPECT_EQ(r.defect_pixels, static_cast<int>(defect.pixels.size()));
    EXPECT_EQ(r.surround_pixels, static_cast<int>(surround.pixels.size()));
    const double c = step / sigma;
    const double se = ltm::tol::cnr_standard_error(c, r.defect_pixels, r.surround_pixels);
    EXPECT_NEAR(r.cnr, c, ltm::tol::kStandardErrors * se) << "se " << se;
    // the noise estimate itself: standard error sigma / sqrt(2 (n - 1))
    EXPECT_NEAR(r.surround_std, sigma,
                ltm::tol::kStandardErrors * sigma / std::sqrt(2.0 * (r.surround_pixels - 1)));
}

// ---- false positives ----

TEST(FalsePositives, MadConstantIsTheGaussianConsistencyFactor) {
    // 1.4826 = 1 / Phi^-1(3/4); Phi^-1(3/4) is the z with P(|Z| > z) = 1/2
    const double exact = 1.0 / ltm::tol::normal_two_sided_quantile(0.5);
    EXPECT_NEAR(ltm::kMadToSigma, exact, ltm::tol::mad_constant_rounding());
}

TEST(FalsePositives, ThreePlantedSpikesInGaussianNoise) {
    // 32 x 32 pixels of N(0.5, 0.01) (seeded) with 3 spikes of +20, -20 and +50 sigma. The chance
    // that pure noise crosses the 5-sigma threshold anywhere is at most 1021 P(|Z| > 5) =
    // 1021 x 5.73e-7 = 5.9e-4 (union bound), asserted below to be negligible; the threshold uses
    // the MAD estimate of sigma, whose relative standard error from 1024 pixels is ~1.17 / sqrt(n)
    // = 3.6% (MAD's Gaussian efficiency is 37%), which moves this to ~1.5e-3 one standard error
    // low. The 3 spikes move the median and MAD by O(3 / n) of sigma: nothing.
    const int W = 32, H = 32, n_noise = W * H - 3;
    const double sigma = 0.01, k = 5.0;
    EXPECT_LT(n_noise * std::erfc(k / std::sqrt(2.0)), ltm::tol::kNegligibleProbability);

    std::vector<float> img(static_cast<std::size_t>(W * H));
    std::mt19937_64 rng(4242);
    std::normal_distribution<double> noise(0.5, sigma);
    for (auto& v : img) v = static_cast<float>(noise(rng));
    img[100] = static_cast<float>(0.5 + 20 * sigma);
    img[555] = static_cast<float>(0.5 - 20 * sigma);
    img[1000] = static_cast<float>(0.5 + 50 * sigma);
    Region all;
    for (int i = 0; i < W * H; ++i) all.pixels.push_back(i);
    EXPECT_EQ(ltm::false_positives(img, all, k), 3);
    EXPECT_EQ(ltm::false_positives(img, all), 3);  // k = 5 is the default
    // without the spikes: none
    Region clean = ltm::subtract(all, Region{{100, 555, 1000}});
    EXPECT_EQ(ltm::false_positives(img, clean, k), 0);
    // NaN pixels are not counted and do not shift the statistics' meaning
    img[7] = kNaNf;
    img[8] = kNaNf;
    EXPECT_EQ(ltm::false_positives(img, all, k), 3);
}

TEST(FalsePositives, SmallSetsByHand) {
    // median 3, |deviations| 2, 1, 0, 1, 97: MAD 1, threshold 5 x 1.4826 = 7.41: only 100
    const std::vector<float> a = {1, 2, 3, 4, 100};
    const Region all5{{0, 1, 2, 3, 4}};
    EXPECT_EQ(ltm::false_positives(a, all5, 5.0), 1);
    EXPECT_EQ(ltm::false_positives(a, all5, 0.0), 4);  // threshold 0: all but the median
    // even count: median 2.5, |deviations| 1.5, 0.5, 0.5, 1.5: MAD 1; k = 1 -> threshold 1.4826
    // catches 1 and 4 (1.5 away), k = 5 none
    const Region first4{{0, 1, 2, 3}};
    EXPECT_EQ(ltm::false_positives(a, first4, 1.0), 2);
    EXPECT_EQ(ltm::false_positives(a, first4, 5.0), 0);
    // empty or all-NaN: nothing to count
    EXPECT_EQ(ltm::false_positives(a, Region{}, 5.0), 0);
    EXPECT_EQ(ltm::false_positives(std::vector<float>{kNaNf, kNaNf}, Region{{0, 1}}, 5.0), 0);
    // infinite pixels take part and count
    const std::vector<float> b = {1, 2, 3, 4, std::numeric_limits<float>::infinity()};
    EXPECT_EQ(ltm::false_positives(b, all5, 5.0), 1);
}

TEST(FalsePositives, ZeroMadCountsEveryPixelOffTheMedian) {
    // a noise-free image (MAD = 0): any pixel that differs from the median counts, whatever k
    std::vector<float> img(100, 0.5f);
    img[13] = 0.5000001f;
    img[77] = 0.25f;
    Region all;
    for (int i = 0; i < 100; ++i) all.pixels.push_back(i);
    EXPECT_EQ(ltm::false_positives(img, all, 5.0), 2);
    EXPECT_EQ(ltm::false_positives(img, all, 1000.0), 2);
    EXPECT_EQ(ltm::false_positives(std::vector<float>(100, 0.5f), all, 5.0), 0);
}

TEST(FalsePositives, BadArguments) {
    const std::vector<float> img = {1, 2, 3};
    EXPECT_THROW(ltm::false_positives(img, Region{{0, 3}}, 5.0), std::invalid_argument);
    EXPECT_THROW(ltm::false_positives(img, Region{{0, 1}}, -1.0), std::invalid_argument);
    EXPECT_THROW(ltm::false_positives(img, Region{{0, 1}}, std::nan("")), std::invalid_argument);
}
