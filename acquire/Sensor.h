#pragma once
// The instrument a real acquisition goes through: a programmable display (LCD) that turns
// command values into radiance, and a camera that turns the radiance T x reaching a pixel into
// a noisy, quantised number. docs/acquisition.md gives the defaults' sources.
//
// Units. T is defined for display pixels emitting radiance 1 (docs/conventions.md), so radiances
// here are relative to the display's white: a camera pixel whose row of T sums to s sees s under
// an all-white display.
//
// Display: command v in [0, 1] is quantised to `bits` (v_q = round(v (2^bits - 1)) / (2^bits - 1))
// and emits
//     L(v) = b + (1 - b) v_q^gamma,     b = black_level = 1 / contrast_ratio,
// so L(0) = b (an LCD's backlight leaks through a black pixel), L(1) = 1.
//
// Camera, per pixel and exposure, for incident radiance y >= 0 (the pixel's y = T L(x)):
//     signal electrons    S ~ Poisson(full_well * exposure * y + dark_level)      shot noise
//     read noise          R ~ Normal(0, read_noise^2)
//     digital number      DN = clamp(round((S + R) / g), 0, 2^bits - 1),  g = full_well / (2^bits - 1)
// (the ADC's gain maps the full well onto the top code, so a saturated pixel reads 2^bits - 1).
// The calibrated estimate of y that decoders see (dark frame subtracted, gain divided out):
//     y_hat = (g DN - dark_level) / (full_well * exposure),
// unbiased below saturation up to the rounding (|bias| <= g / 2 / (full_well exposure), and 0 for
// continuous noise much wider than g, Sheppard's correction), with variance
//     var(y_hat) = (full_well exposure y + dark_level + read_noise^2 + g^2 / 12) / (full_well exposure)^2
// (Poisson variance = mean; independent noises add; uniform rounding error g^2 / 12).
//
// Random numbers come from counter-based streams (acquire/CounterRng.h), one per (seed, pattern,
// camera pixel): the same seed gives bit-identical images whatever the thread count.
#include <cstdint>
#include <string>
#include <vector>

#include "acquire/CounterRng.h"

namespace ltm::acquire {

struct CameraModel {
    double full_well = 10500;   // electrons at saturation
    double exposure = 0.5;      // fraction of the full well collected at y = 1 (no saturation below y = 2)
    double read_noise = 2.4;    // electrons rms
    double dark_level = 1.0;    // mean dark electrons per exposure (dark current x time), Poisson
    int bits = 12;              // ADC: 8, 10, 12 or 16
};

struct DisplayModel {
    double black_level = 0.001;  // L(0) relative to white: 1 / contrast ratio (1000:1)
    double gamma = 2.2;          // L ~ v^gamma
    int bits = 8;                // command values per channel
};

struct SensorModel {
    CameraModel camera;
    DisplayModel display;
    std::uint64_t seed = 1;
    bool noise_free = false;  // for tests and references: y_hat = y exactly (no noise, no quantisation)
};

// The first problem with the parameters, naming the key as the YAML section spells it
// ("camera.read_noise: must be >= 0 (got -1)"), or "" if they are valid: full_well > 0 and finite,
// exposure > 0 and finite, read_noise >= 0, dark_level >= 0 (finite), camera bits in {8, 10, 12,
// 16}, 0 <= black_level < 1, gamma > 0 (finite), display bits in [1, 16].
std::string check(const SensorModel& m);

// The display's radiance for command value v (clamped to [0, 1]).
double display_radiance(const DisplayModel& d, double v);

// The command value whose radiance is b + (1 - b) t for t in [0, 1], before the display's
// quantisation: t^(1 / gamma). Patterns that want a linear radiance (phase shifting) are drawn
// through it, as a calibrated system does.
double linear_command(const DisplayModel& d, double t);

// A Poisson(lambda) variate, lambda >= 0: inversion by sequential search for lambda < 12 (one
// uniform; the cumulative sums stay accurate since e^-12 >> 2^-53), above it W. Hoermann's
// transformed rejection with squeeze, PTRS ("The transformed rejection method for generating
// Poisson random variables", Insurance: Mathematics and Economics 12 (1993) 39-45, valid for
// lambda >= 10; the constants of his Table 1, as numpy's random_poisson_ptrs uses them).
double poisson(double lambda, CounterRng& rng);
// One Poisson law drawn from many times (a brute-force acquisition's dark measurements all share
// theirs): for lambda < 12 the cumulative table F(0..1000) summed exactly as poisson's sequential
// search sums it, so a draw is the same number poisson(lambda, rng) gives for the same stream;
// otherwise poisson itself.
class PoissonLaw {
public:
    explicit PoissonLaw(double lambda);
    double sample(CounterRng& rng) const;
    double mean() const { return lambda_; }

private:
    double lambda_;
    std::vector<double> cdf_;  // empty for lambda >= 12 or lambda <= 0
};

// A standard normal variate (Box-Muller, two uniforms, the cosine branch).
double gaussian(CounterRng& rng);

// Electrons S + R (above) for radiance y (negative y counts as 0).
double electrons(const CameraModel& c, double y, CounterRng& rng);
// DN for a number of electrons (above).
double digital_number(const CameraModel& c, double e);
// The ADC gain g, electrons per DN.
double adc_gain(const CameraModel& c);

// One calibrated measurement y_hat of radiance y (above); y itself when noise_free.
double measure(const SensorModel& m, double y, CounterRng& rng);
// The same, for a radiance whose signal law (fe y + dark_level, PoissonLaw) is already tabulated:
// the same value measure gives for that y and stream. Not for noise_free models.
double measure(const SensorModel& m, const PoissonLaw& signal, CounterRng& rng);

// var(y_hat) for true radiance y (above, below saturation); 0 when noise_free.
double measurement_variance(const SensorModel& m, double y);

}  // namespace ltm::acquire
