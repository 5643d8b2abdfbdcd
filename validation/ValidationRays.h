#pragma once
// The rays `ltmsim validate` traces with both the tracer and the analytic reference solver.
//
// Categories (ValidationRays.cpp explains how each is built):
//   "axial"    the optical axis ray (origin (0, 0, z0), direction (0, 0, 1), exactly) and rays
//              parallel to it on a square grid over the aperture (rho <= 0.97 a);
//   "tilted"   rays at angles up to asin(camera NA) and a few larger, up to 10 degrees;
//   "near-rim" rays parallel to the axis at rho in (0.98 a, a), and four exactly at
//              rho = a - 1e-6 a (on the x and y axes);
//   "grazing"  rays meeting the front face at 75..89.5 degrees of incidence, from the side;
//   "bubble"   rays whose segment in the glass goes through each enclosed bubble's centre or at
//              offsets up to 0.999 of its half-width (found by inverse refraction at the front);
//   "particle" the same for absorbing particles (only when the scene has particles);
//   "tir"      rays whose reference path has at least one total internal reflection, selected by
//              the analytic solver from candidate families (see ValidationRays.cpp).
// Origins are in air: z0 = (the object's smallest z) - 1 mm for all but "grazing" and "tir",
// which start in air elsewhere (checked with AnalyticScene::medium_at). Directions are unit.
// The set is deterministic (no random number library; a fixed integer hash) and its size grows
// linearly with `density` (density 1: ~200 rays, depending on the number of defects).
#include <string>
#include <vector>

#include "geometry/Vec3.h"
#include "scene/Scene.h"

namespace ltm::validation {

struct ValidationRay {
    Vec3 origin, direction;
    std::string category;
};

// Precondition: supports(scene) (throws std::invalid_argument otherwise, and for density < 1).
std::vector<ValidationRay> validation_rays(const Scene& scene, int density);

}  // namespace ltm::validation
