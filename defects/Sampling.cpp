#include "defects/Sampling.h"

#include <cmath>
#include <fmt/format.h>
#include <random>
#include <stdexcept>

namespace ltm {

namespace {
// A double uniform in [0, 1) from the top 53 bits.
double uniform01(std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; }
}  // namespace

std::vector<Defect> sample_bubbles(const Lens& lens, const BubblePopulation& p) {
    std::mt19937_64 g(p.seed);
    const double a = lens.aperture_radius();
    const double zlo = std::fmin(lens.z_front(0), lens.z_front(a)), zhi = std::fmax(lens.z_back(0), lens.z_back(a));
    std::vector<Defect> out;
    out.reserve(static_cast<size_t>(p.count));
    for (int i = 0; i < p.count; ++i) {
        bool placed = false;
        for (int attempt = 0; attempt < 1000 && !placed; ++attempt) {
            const double r = p.min_radius + (p.max_radius - p.min_radius) * uniform01(g);
            const double x = a * (2 * uniform01(g) - 1), y = a * (2 * uniform01(g) - 1);
            const double z = zlo + (zhi - zlo) * uniform01(g);
            const Vec3 c{x, y, z};
            if (lens.signed_distance(c) - r <= p.min_clearance) continue;
            bool clash = false;
            for (const auto& o : out)
                clash = clash || distance(o.center, c) <= o.semi_axes.x + r + p.min_clearance;
            if (clash) continue;
            Defect d;
            d.type = DefectType::Bubble;
            d.center = c;
            d.semi_axes = {r, r, r};
            out.push_back(d);
            placed = true;
        }
        if (!placed)
            throw std::runtime_error(fmt::format("could not place bubble {} of {} after 1000 attempts", i + 1, p.count));
    }
    return out;
}

}  // namespace ltm
