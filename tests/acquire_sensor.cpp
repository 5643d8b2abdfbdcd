// The sensor and display model (acquire/Sensor.h) against its closed forms: the mean and variance
// of the camera's electrons (Poisson shot noise + Gaussian read noise) and of the calibrated,
// quantised measurement, by Z-tests on seeded counter-based streams; the display's black level,
// gamma and its linearising command; the streams' independence from the visiting order.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "acquire/Sensor.h"
#include "tests/Tolerances.h"

namespace {

using namespace ltm::acquire;

// Number of statistics tested below (two per case: mean and variance), for Bonferroni.
constexpr int kPoissonCases = 6, kElectronCases = 6, kMeasureCases = 3;
constexpr long kTests = 2 * (kPoissonCases + kElectronCases + kMeasureCases);
constexpr long kSamples = 200000;

struct Moments {
    double mean = 0, var = 0;
};

template <class Draw>
Moments sample(Draw draw) {
    // Two passes in double: the mean, then the squared deviations.
    std::vector<double> x(kSamples);
    for (long i = 0; i < kSamples; ++i) x[static_cast<std::size_t>(i)] = draw(i);
    Moments m;
    for (double v : x) m.mean += v;
    m.mean /= kSamples;
    for (double v : x) m.var += (v - m.mean) * (v - m.mean);
    m.var /= kSamples - 1;
    return m;
}

// Z statistics of the sample mean and sample variance against the closed-form mean mu, variance
// sigma2 and central fourth moment mu4 (Tolerances.h, "acquire_*").
void expect_moments(const Moments& m, double mu, double sigma2, double mu4, const char* what) {
    const double n = kSamples;
    const double z_mean = (m.mean - mu) / std::sqrt(sigma2 / n);
    const double var_se = std::sqrt((mu4 - sigma2 * sigma2 * (n - 3) / (n - 1)) / n);
    const double z_var = (m.var - sigma2) / var_se;
    const double z = ltm::tol::bonferroni_z(kTests);
    EXPECT_LT(std::fabs(z_mean), z) << what << ": mean " << m.mean << " vs " << mu;
    EXPECT_LT(std::fabs(z_var), z) << what << ": variance " << m.var << " vs " << sigma2;
}

// Poisson(L): mean = variance = L, central fourth moment L (1 + 3 L).
// Both branches: inversion below 12, PTRS from 12 on (the cases straddle the switch).
TEST(Sensor, PoissonMeanAndVarianceMatchTheClosedForm) {
    const double lambdas[kPoissonCases] = {0.3, 4.0, 11.9, 12.1, 60.0, 5000.0};
    for (int c = 0; c < kPoissonCases; ++c) {
        const double L = lambdas[c];
        const Moments m = sample([&](long i) {
            CounterRng rng(7, static_cast<std::uint64_t>(c), static_cast<std::uint64_t>(i));
            return poisson(L, rng);
        });
        expect_moments(m, L, L, L * (1 + 3 * L), ("Poisson " + std::to_string(L)).c_str());
    }
}

// Electrons S + R: S ~ Poisson(fe y + d), R ~ N(0, r^2) independent: mean fe y + d, variance
// L + r^2 (L = fe y + d), central fourth moment L (1 + 3 L) + 6 L r^2 + 3 r^4 (the fourth
// central moment of a sum of independent variables: mu4(S) + 6 var(S) var(R) + mu4(R)).
TEST(Sensor, ElectronsMeanAndVarianceMatchShotPlusReadNoise) {
    CameraModel cam;
    cam.full_well = 10000;
    cam.exposure = 0.5;
    cam.read_noise = 2.5;
    cam.dark_level = 1.5;
    const double ys[kElectronCases] = {0.0, 1e-4, 2e-3, 0.05, 0.4, 1.0};
    for (int c = 0; c < kElectronCases; ++c) {
        const double L = cam.full_well * cam.exposure * ys[c] + cam.dark_level, r2 = cam.read_noise * cam.read_noise;
        const Moments m = sample([&](long i) {
            CounterRng rng(11, static_cast<std::uint64_t>(c), static_cast<std::uint64_t>(i));
            return electrons(cam, ys[c], rng);
        });
        expect_moments(m, L, L + r2, L * (1 + 3 * L) + 6 * L * r2 + 3 * r2 * r2, ("electrons at y = " + std::to_string(ys[c])).c_str());
    }
}

// The calibrated measurement y_hat = (g DN - d) / (fe): unbiased, variance
// (fe y + d + r^2 + g^2 / 12) / fe^2 (Sensor.h). The rounding to DN is uniform to within
// exp(-2 pi^2 sigma^2 / g^2) when the noise sigma (in electrons) is wide against the step g
// (Sheppard's correction; W. F. Sheppard, Proc. London Math. Soc. 29 (1898) 353-380): the cases
// keep sigma / g >= 1.2, so the deviation is below e^-28. The fourth moment is taken as that of
// the continuous noise plus the uniform rounding (mu4 of U(-g/2, g/2) = g^4 / 80).
TEST(Sensor, MeasurementIsUnbiasedWithTheStatedVariance) {
    struct Case {
        int bits;
        double y;
    };
    const Case cases[kMeasureCases] = {{8, 0.5}, {12, 0.05}, {16, 0.9}};
    for (int c = 0; c < kMeasureCases; ++c) {
        SensorModel s;
        s.camera.bits = cases[c].bits;
        s.seed = 3;
        const double fe = s.camera.full_well * s.camera.exposure, g = adc_gain(s.camera);
        const double L = fe * cases[c].y + s.camera.dark_level, r2 = s.camera.read_noise * s.camera.read_noise;
        ASSERT_GE(std::sqrt(L + r2) / g, 1.2) << "the case must keep the noise wide against the step";
        const Moments m = sample([&](long i) {
            CounterRng rng(s.seed, static_cast<std::uint64_t>(100 + c), static_cast<std::uint64_t>(i));
            return measure(s, cases[c].y, rng);
        });
        const double sigma2_e = L + r2 + g * g / 12;
        const double mu4_e = L * (1 + 3 * L) + 6 * L * r2 + 3 * r2 * r2 + 6 * (L + r2) * g * g / 12 + std::pow(g, 4) / 80;
        expect_moments(m, cases[c].y, sigma2_e / (fe * fe), mu4_e / std::pow(fe, 4),
                       ("measurement, " + std::to_string(cases[c].bits) + " bits").c_str());
        EXPECT_NEAR(measurement_variance(s, cases[c].y), sigma2_e / (fe * fe), 1e-15 * sigma2_e / (fe * fe));
    }
}

TEST(Sensor, SaturatedPixelsReadTheTopCode) {
    CameraModel cam;  // 12 bits
    CounterRng rng(1, 2, 3);
    EXPECT_EQ(digital_number(cam, electrons(cam, 5.0, rng)), 4095.0);  // 2.5 full wells
    EXPECT_EQ(digital_number(cam, -50.0), 0.0);                        // read noise below zero clamps
}

TEST(Sensor, DisplayBlackLevelGammaAndLinearisingCommand) {
    DisplayModel d;
    d.black_level = 0.002;
    d.gamma = 2.2;
    d.bits = 16;
    EXPECT_EQ(display_radiance(d, 0.0), 0.002);
    EXPECT_DOUBLE_EQ(display_radiance(d, 1.0), 1.0);
    // v = 0.5 at 16 bits is 32768 / 65535 (the nearest code): L = b + (1 - b) (32768 / 65535)^2.2.
    EXPECT_DOUBLE_EQ(display_radiance(d, 0.5), 0.002 + 0.998 * std::pow(32768.0 / 65535.0, 2.2));
    // The linearising command gives radiance b + (1 - b) t up to the quantisation: |dL| <= g 2^-17.
    for (double t : {0.0, 0.1, 0.37, 0.8, 1.0})
        EXPECT_NEAR(display_radiance(d, linear_command(d, t)), 0.002 + 0.998 * t, 2.2 * std::ldexp(1.0, -17)) << t;
}

TEST(Sensor, StreamsDependOnTheirIndicesOnly) {
    // The same (seed, pattern, pixel) gives the same draws however many other streams were used
    // in between, and neighbouring streams differ.
    CounterRng a(5, 10, 20), b(5, 10, 20), c(5, 10, 21), d(5, 11, 20), e(6, 10, 20);
    for (int i = 0; i < 100; ++i) CounterRng(5, 10, static_cast<std::uint64_t>(i)).next();
    const std::uint64_t va = a.next();
    EXPECT_EQ(va, b.next());
    EXPECT_NE(va, c.next());
    EXPECT_NE(va, d.next());
    EXPECT_NE(va, e.next());
    EXPECT_NE(CounterRng(5, 10, 20).next(), CounterRng(5, 20, 10).next());
}

TEST(Sensor, CheckNamesTheBadKey) {
    SensorModel s;
    EXPECT_EQ(check(s), "");
    s.camera.read_noise = -1;
    EXPECT_EQ(check(s), "camera.read_noise: must be a finite number >= 0 (got -1)");
    s = {};
    s.camera.bits = 0;
    EXPECT_EQ(check(s), "camera.bits: must be 8, 10, 12 or 16 (got 0)");
    s = {};
    s.display.black_level = 1;
    EXPECT_EQ(check(s), "display.black_level: must be in [0, 1) (got 1)");
}

}  // namespace

namespace {

// The tabulated law gives exactly poisson()'s draws for the same streams (the brute-force
// acquisition relies on it to be the same measurement), on both sides of the switch to PTRS.
TEST(Sensor, TabulatedPoissonLawDrawsWhatPoissonDraws) {
    for (double L : {0.0, 0.7, 5.25, 11.99, 12.0, 40.0}) {
        const ltm::acquire::PoissonLaw law(L);
        for (std::uint64_t i = 0; i < 20000; ++i) {
            ltm::acquire::CounterRng a(9, 1, i), b(9, 1, i);
            ASSERT_EQ(law.sample(a), ltm::acquire::poisson(L, b)) << L << " " << i;
        }
    }
}

}  // namespace
