#include "trace/Optics.h"

#include <cmath>

namespace ltm {

FresnelResult fresnel(double cos_i, double eta) {
    FresnelResult r;
    cos_i = std::fmin(1.0, std::fabs(cos_i));
    // 1 - cos^2 written as (1 - c)(1 + c) keeps its relative precision near normal incidence.
    const double sin2_t = eta * eta * (1.0 - cos_i) * (1.0 + cos_i);
    if (sin2_t >= 1.0) {
        r.total_internal_reflection = true;
        return r;
    }
    const double cos_t = std::sqrt((1.0 - sin2_t));
    const double rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    const double rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    r.reflectance = 0.5 * (rs * rs + rp * rp);
    r.cos_t = cos_t;
    return r;
}

}  // namespace ltm
