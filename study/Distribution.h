#pragma once
// The random parameters of a dataset spec (docs/dataset.md, "Distributions"): numbers, counts and
// choices, each drawn from a counter-based stream (trace/Rng.h) so that a sample's draws depend on
// its seed alone. Every draw consumes a fixed number of variates except the Poisson count
// (Knuth's product of uniforms, mean + 1 variates on average) and redraws.
#include <string>
#include <vector>

#include "trace/Rng.h"

namespace ltm {

// A real parameter: a constant, or uniform, log-uniform or normal.
//
// The values a parameter may take (its `range`: any, positive, or >= 0, set by the key it belongs
// to) bound the law: the spec's parser refuses a constant or a uniform range outside them, so only
// a normal can draw outside, and it is truncated to the range (draw again until the value is in
// it, docs/dataset.md). cdf() is the law as drawn, truncation included.
struct Distribution {
    enum class Kind { Constant, Uniform, LogUniform, Normal };
    enum class Range { Any, Positive, NonNegative };
    Kind kind = Kind::Constant;
    double a = 0, b = 0;  // constant: a; uniform, log_uniform: [a, b]; normal: mean a, sd b
    Range range = Range::Any;

    static Distribution constant(double v) { return {Kind::Constant, v, v}; }
    // One draw, ignoring the range. Constant: 0 variates; uniform: a + (b - a) u; log-uniform:
    // a (b / a)^u; normal: Box-Muller, a + b sqrt(-2 ln(1 - u1)) cos(2 pi u2). 1, 1 and 2 variates.
    double draw(Rng& rng) const;
    // Whether x lies in the range.
    bool admits(double x) const;
    // P(X <= x) for the law truncated to the range. Uniform: (x - a) / (b - a); log-uniform:
    // ln(x / a) / ln(b / a); normal: with S(x) = erfc((x - a) / (b sqrt 2)) / 2 its upper tail and
    // L its range's lower end, 1 - S(x) / S(L) (1 - S(x) without a lower end); a constant: the step
    // at a. Clamped to [0, 1].
    double cdf(double x) const;
    // Whether the law is continuous (a constant, or a uniform range of zero width, is not).
    bool continuous() const { return kind == Kind::Normal || (kind != Kind::Constant && b > a); }
    // The support: [a, b], or (-inf, inf) for the normal.
    double lo() const;
    double hi() const;
    // As the spec writes it: 0.3, {uniform: [0.1, 0.2]}, ...
    std::string to_string() const;
};

// The number of defects of a kind in a sample.
struct CountDistribution {
    enum class Kind { Fixed, Poisson, UniformInt };
    Kind kind = Kind::Fixed;
    int a = 0, b = 0;     // fixed: a; uniform_int: [a, b]
    double mean = 0;      // poisson
    int draw(Rng& rng) const;
    int lo() const { return kind == Kind::Poisson ? 0 : a; }
    std::string to_string() const;
};

// One of a list of words, uniformly; a single word is a constant (0 variates).
struct Choice {
    std::vector<std::string> options;
    const std::string& draw(Rng& rng) const;
    std::string to_string() const;
};

}  // namespace ltm
