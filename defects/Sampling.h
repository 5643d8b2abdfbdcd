#pragma once
// Defects drawn from distributions, for datasets and stress tests. Deterministic for a seed on
// every platform: the generator is std::mt19937_64 (fully specified by the standard) and the
// uniform variates are built from its bits here, not by std::uniform_real_distribution (whose
// algorithm is implementation-defined).
#include <cstdint>
#include <vector>

#include "defects/Defect.h"
#include "geometry/Lens.h"

namespace ltm {

struct BubblePopulation {
    int count = 100;
    double min_radius = 0.02, max_radius = 0.1;  // mm, radius uniform in [min, max]
    double min_clearance = 0.0;                  // mm, from the glass boundary and between bubbles
    std::uint64_t seed = 1;
};

// Spherical bubbles with centres uniform in the glass volume (rejection sampling in the bounding
// cylinder), each strictly inside the glass and clear of the others by min_clearance. Throws
// std::runtime_error if `count` cannot be placed within 1000 attempts per bubble.
std::vector<Defect> sample_bubbles(const Lens& lens, const BubblePopulation& p);

}  // namespace ltm
