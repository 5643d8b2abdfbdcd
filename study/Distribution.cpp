#include "study/Distribution.h"

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
