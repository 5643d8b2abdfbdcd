#pragma once
// Traced principal paths against the analytic reference solver, ray by ray (`ltmsim validate`).
#include <map>
#include <string>
#include <vector>

#include "defects/SolidBuilder.h"
#include "scene/Scene.h"
#include "trace/Tracer.h"

namespace ltm::validation {

struct CategoryResult {
    int rays = 0;
    int compared = 0;          // stable rays whose positions and directions were compared
    int ill_conditioned = 0;   // unstable rays (a seam, tangency or critical angle within 1e-7 a)
    int sequence_mismatches = 0;  // stable rays whose surface sequence differs
    int over_tolerance = 0;    // stable rays with an error above their tolerance
    double max_hit_error = 0;  // mm, display hit and vertices
    double max_dir_error = 0;  // rad, final direction
    double max_ratio = 0;      // largest error / tolerance
};

struct ValidationReport {
    Representation representation = Representation::Refined;
    std::map<std::string, CategoryResult> categories;
    CategoryResult total;
    std::vector<std::string> failures;  // one line per failing ray (the first 20)
    bool passed() const { return total.sequence_mismatches == 0 && total.over_tolerance == 0; }
};

// Whether `validate` can check the scene: AnalyticScene's scenes (homogeneous glass with enclosed
// bubbles and particles), and GrinReference's (any index field; inhomogeneities). *why says why not.
bool can_validate(const Scene& scene, std::string* why = nullptr);

// Precondition: can_validate(scene). Traces validation_rays(scene, density) with `representation`
// against AnalyticScene, or, for a scene with an index field or inhomogeneities, against
// GrinReference (the rays then come from the same scene without them, its geometry alone),
// with the tolerances of ValidationTolerance.h: the closed-form GRIN floor, or for TetGen-meshed
// fields the first-order bound of the interpolated index (meshed_position_tolerance).
ValidationReport validate(const Scene& scene, const Solid& solid, Representation representation, int density);

std::string format_report(const ValidationReport& r, bool with_tolerance_verdict);

}  // namespace ltm::validation
