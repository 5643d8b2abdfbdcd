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
struct Distribution {
    enum class Kind { Constant, Uniform, LogUniform, Normal };
    Kind kind = Kind::Constant;
    double a = 0, b = 0;  // constant: a; uniform, log_uniform: [a, b]; normal: mean a, sd b

    static Distribution constant(double v) { return {Kind::Constant, v, v}; }
    // Constant: 0 variates; uniform: a + (b - a) u; log-uniform: a (b / a)^u; normal: Box-Muller,
    // a + b sqrt(-2 ln(1 - u1)) cos(2 pi u2). 1, 1 and 2 variates.
    double draw(Rng& rng) const;
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
