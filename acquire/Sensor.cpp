#include "acquire/Sensor.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace ltm::acquire {

namespace {
constexpr double kInversionBelow = 12;  // poisson: sequential search below, PTRS from here on
constexpr int kInversionMaxK = 1000;     // the search's cap (reached only as F stalls below u ~ 1 - 2^-53)
}  // namespace


std::string check(const SensorModel& m) {
    const CameraModel& c = m.camera;
    const DisplayModel& d = m.display;
    auto bad = [](const char* key, const char* rule, double v) { return fmt::format("{}: must be {} (got {})", key, rule, v); };
    if (!(c.full_well > 0) || !std::isfinite(c.full_well)) return bad("camera.full_well", "a finite number > 0", c.full_well);
    if (!(c.exposure > 0) || !std::isfinite(c.exposure)) return bad("camera.exposure", "a finite number > 0", c.exposure);
    if (!(c.read_noise >= 0) || !std::isfinite(c.read_noise)) return bad("camera.read_noise", "a finite number >= 0", c.read_noise);
    if (!(c.dark_level >= 0) || !std::isfinite(c.dark_level)) return bad("camera.dark_level", "a finite number >= 0", c.dark_level);
    if (c.bits != 8 && c.bits != 10 && c.bits != 12 && c.bits != 16)
        return fmt::format("camera.bits: must be 8, 10, 12 or 16 (got {})", c.bits);
    if (!(d.black_level >= 0 && d.black_level < 1)) return bad("display.black_level", "in [0, 1)", d.black_level);
    if (!(d.gamma > 0) || !std::isfinite(d.gamma)) return bad("display.gamma", "a finite number > 0", d.gamma);
    if (d.bits < 1 || d.bits > 16) return fmt::format("display.bits: must be in [1, 16] (got {})", d.bits);
    return "";
}

double display_radiance(const DisplayModel& d, double v) {
    const double top = std::ldexp(1.0, d.bits) - 1;
    const double q = std::round(std::clamp(v, 0.0, 1.0) * top) / top;
    return d.black_level + (1 - d.black_level) * std::pow(q, d.gamma);
}

double linear_command(const DisplayModel& d, double t) { return std::pow(std::clamp(t, 0.0, 1.0), 1 / d.gamma); }

double poisson(double lambda, CounterRng& rng) {
    if (!(lambda > 0)) return 0;
    if (lambda < kInversionBelow) {
        // Sequential search: the smallest k with F(k) >= u.
        const double u = rng.uniform();
        double p = std::exp(-lambda), F = p;
        int k = 0;
        while (u > F && k < kInversionMaxK) {
            ++k;
            p *= lambda / k;
            F += p;
        }
        return k;
    }
    const double slam = std::sqrt(lambda), loglam = std::log(lambda);
    const double b = 0.931 + 2.53 * slam, a = -0.059 + 0.02483 * b;
    const double invalpha = 1.1239 + 1.1328 / (b - 3.4), vr = 0.9277 - 3.6224 / (b - 2);
    for (;;) {
        const double U = rng.uniform() - 0.5, V = rng.uniform();
        const double us = 0.5 - std::fabs(U);
        const double k = std::floor((2 * a / us + b) * U + lambda + 0.43);
        if (us >= 0.07 && V <= vr) return k;
        if (k < 0 || (us < 0.013 && V > us)) continue;
        if (std::log(V) + std::log(invalpha) - std::log(a / (us * us) + b) <= -lambda + k * loglam - std::lgamma(k + 1))
            return k;
    }
}

PoissonLaw::PoissonLaw(double lambda) : lambda_(lambda) {
    if (!(lambda > 0) || lambda >= kInversionBelow) return;
    cdf_.resize(kInversionMaxK + 1);
    double p = std::exp(-lambda), F = p;
    cdf_[0] = F;
    for (int k = 1; k <= kInversionMaxK; ++k) {
        p *= lambda / k;
        F += p;
        cdf_[static_cast<std::size_t>(k)] = F;
    }
}

double PoissonLaw::sample(CounterRng& rng) const {
    if (cdf_.empty()) return poisson(lambda_, rng);
    const double u = rng.uniform();
    int k = 0;
    while (u > cdf_[static_cast<std::size_t>(k)] && k < kInversionMaxK) ++k;
    return k;
}

double gaussian(CounterRng& rng) {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
}

double adc_gain(const CameraModel& c) { return c.full_well / (std::ldexp(1.0, c.bits) - 1); }

double electrons(const CameraModel& c, double y, CounterRng& rng) {
    const double S = poisson(c.full_well * c.exposure * std::max(y, 0.0) + c.dark_level, rng);
    return S + (c.read_noise > 0 ? c.read_noise * gaussian(rng) : 0.0);
}

double digital_number(const CameraModel& c, double e) {
    return std::clamp(std::round(e / adc_gain(c)), 0.0, std::ldexp(1.0, c.bits) - 1);
}

namespace {
double calibrated(const CameraModel& c, double e) {
    return (adc_gain(c) * digital_number(c, e) - c.dark_level) / (c.full_well * c.exposure);
}
}  // namespace

double measure(const SensorModel& m, double y, CounterRng& rng) {
    if (m.noise_free) return y;
    return calibrated(m.camera, electrons(m.camera, y, rng));
}

double measure(const SensorModel& m, const PoissonLaw& signal, CounterRng& rng) {
    const CameraModel& c = m.camera;
    const double S = signal.sample(rng);
    return calibrated(c, S + (c.read_noise > 0 ? c.read_noise * gaussian(rng) : 0.0));
}

double measurement_variance(const SensorModel& m, double y) {
    if (m.noise_free) return 0;
    const CameraModel& c = m.camera;
    const double fe = c.full_well * c.exposure, g = adc_gain(c);
    return (fe * std::max(y, 0.0) + c.dark_level + c.read_noise * c.read_noise + g * g / 12) / (fe * fe);
}

}  // namespace ltm::acquire
