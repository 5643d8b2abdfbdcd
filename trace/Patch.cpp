#include "trace/Patch.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "trace/Intersect.h"
#include "trace/TraceTolerance.h"

namespace ltm {

std::vector<Patch> object_patches(const Lens& lens) {
    const double a = lens.aperture_radius();
    std::vector<Patch> out(3);
    const double zf0 = lens.z_front(0), zfa = lens.z_front(a), zb0 = lens.z_back(0), zba = lens.z_back(a);
    const auto patch = [&](Patch::Kind kind, const Surface& s, int tag, double z_vertex, double z_lo, double z_hi) {
        Patch p;
        p.kind = kind;
        p.surface = s;
        p.tag = tag;
        p.a = a;
        p.z_vertex = z_vertex;
        p.z_lo = z_lo;
        p.z_hi = z_hi;
        return p;
    };
    out[0] = patch(Patch::Kind::Cap, lens.front_surface(), 0, zf0, 0, 0);
    out[1] = patch(Patch::Kind::Cap, lens.back_surface(), 1, zb0, 0, 0);
    out[2] = patch(Patch::Kind::Rim, lens.rim_surface(), 2, 0, zfa, zba);
    out[0].bounds = {{-a, -a, std::fmin(zf0, zfa)}, {a, a, std::fmax(zf0, zfa)}};
    out[1].bounds = {{-a, -a, std::fmin(zb0, zba)}, {a, a, std::fmax(zb0, zba)}};
    out[2].bounds = {{-a, -a, zfa}, {a, a, zba}};
    for (auto& p : out) p.finalize();
    return out;
}

void Patch::finalize() {
    constexpr double slack = 8 * std::numeric_limits<double>::epsilon();
    rho2_max = (a * (1 + slack)) * (a * (1 + slack));
    rho2_inside = (a * (1 - trace_tol::kRimInsideMargin)) * (a * (1 - trace_tol::kRimInsideMargin));
    const double zs = slack * (std::fabs(z_lo) + std::fabs(z_hi) + a);
    z_min = z_lo - zs;
    z_max = z_hi + zs;
    if (!bounds.empty()) {
        centre = (bounds.lo + bounds.hi) * 0.5;
        bounding_radius = 0.5 * length(bounds.hi - bounds.lo) * (1 + slack);
        const Vec3 ext = bounds.hi - bounds.lo;
        const double m = trace_tol::kCullMargin *
                         (std::max({ext.x, ext.y, ext.z}) +
                          std::max({std::fabs(bounds.lo.x), std::fabs(bounds.lo.y), std::fabs(bounds.lo.z),
                                    std::fabs(bounds.hi.x), std::fabs(bounds.hi.y), std::fabs(bounds.hi.z)}));
        cull = {bounds.lo - Vec3{m, m, m}, bounds.hi + Vec3{m, m, m}};
    }
}

}  // namespace ltm
