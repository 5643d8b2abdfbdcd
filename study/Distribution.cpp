#include "study/Distribution.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>

#include "geometry/Vec3.h"

namespace ltm {

double Distribution::draw(Rng& rng) const {
    switch (kind) {
        case Kind::Constant: return a;
        case Kind::Uniform: return a + (b - a) * rng.uniform();
        case Kind::LogUniform: return a * std::pow(b / a, rng.uniform());
        case Kind::Normal: {
            const double u1 = rng.uniform(), u2 = rng.uniform();
            return a + b * std::sqrt(-2 * std::log1p(-u1)) * std::cos(2 * kPi * u2);
        }
    }
    return a;
}

bool Distribution::admits(double x) const {
    if (!std::isfinite(x)) return false;
    switch (range) {
        case Range::Any: return true;
        case Range::Positive: return x > 0;
        case Range::NonNegative: return x >= 0;
    }
    return true;
}

double Distribution::cdf(double x) const {
    if (std::isnan(x)) return NAN;
    switch (kind) {
        case Kind::Constant: return x < a ? 0.0 : 1.0;
        case Kind::Uniform:
            if (!(b > a)) return x < a ? 0.0 : 1.0;
            return std::clamp((x - a) / (b - a), 0.0, 1.0);
        case Kind::LogUniform:
            if (!(b > a)) return x < a ? 0.0 : 1.0;
            if (!(x > a)) return 0.0;
            return std::clamp(std::log(x / a) / std::log(b / a), 0.0, 1.0);
        case Kind::Normal: {
            // Upper tails through erfc keep their relative precision where they are small (a
            // normal mostly below the range's end, truncated to its far tail).
            const auto upper = [&](double t) { return 0.5 * std::erfc((t - a) / (b * std::sqrt(2.0))); };
            if (range == Range::Any) return std::clamp(1.0 - upper(x), 0.0, 1.0);
            if (x <= 0) return 0.0;  // below a positive or non-negative range (0 itself has measure 0)
            return std::clamp(1.0 - upper(x) / upper(0.0), 0.0, 1.0);
        }
    }
    return NAN;
}

double Distribution::lo() const { return kind == Kind::Normal ? -std::numeric_limits<double>::infinity() : a; }
double Distribution::hi() const { return kind == Kind::Normal ? std::numeric_limits<double>::infinity() : b; }

std::string Distribution::to_string() const {
    switch (kind) {
        case Kind::Constant: return fmt::format("{}", a);
        case Kind::Uniform: return fmt::format("{{uniform: [{}, {}]}}", a, b);
        case Kind::LogUniform: return fmt::format("{{log_uniform: [{}, {}]}}", a, b);
        case Kind::Normal: return fmt::format("{{normal: [{}, {}]}}", a, b);
    }
    return "?";
}

int CountDistribution::draw(Rng& rng) const {
    switch (kind) {
        case Kind::Fixed: return a;
        case Kind::UniformInt: return a + static_cast<int>(rng.uniform() * (b - a + 1));
        case Kind::Poisson: {
            // Knuth: the number of uniforms whose running product stays above e^-mean, minus one.
            // Exact for the means the spec allows (<= 16: e^-16 is far above the smallest double).
            const double limit = std::exp(-mean);
            int k = 0;
            for (double p = rng.uniform(); p > limit; p *= rng.uniform()) ++k;
            return k;
        }
    }
    return a;
}

std::string CountDistribution::to_string() const {
    switch (kind) {
        case Kind::Fixed: return std::to_string(a);
        case Kind::UniformInt: return fmt::format("{{uniform_int: [{}, {}]}}", a, b);
        case Kind::Poisson: return fmt::format("{{poisson: {}}}", mean);
    }
    return "?";
}

const std::string& Choice::draw(Rng& rng) const {
    if (options.size() == 1) return options.front();
    const size_t i = std::min(options.size() - 1, static_cast<size_t>(rng.uniform() * static_cast<double>(options.size())));
    return options[i];
}

std::string Choice::to_string() const {
    if (options.size() == 1) return options.front();
    std::string s = "{choice: [";
    for (size_t i = 0; i < options.size(); ++i) s += (i ? ", " : "") + options[i];
    return s + "]}";
}

}  // namespace ltm
