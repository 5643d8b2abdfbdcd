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

// Precondition: supports(scene). Traces validation_rays(scene, density) with `representation`.
ValidationReport validate(const Scene& scene, const Solid& solid, Representation representation, int density);

std::string format_report(const ValidationReport& r, bool with_tolerance_verdict);

}  // namespace ltm::validation
