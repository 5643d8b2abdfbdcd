#pragma once
// THE tolerance of `ltmsim validate`: how far a traced path may be from the analytic reference
// path (validation/AnalyticScene.h) of the same ray. Defined here and nowhere else.
//
//   position (vertices, display hit):  tol_pos(n) = C(n) u L (1 + kappa)      [mm]
//   final direction:                   tol_dir(n) = C(n) u (1 + kappa_dir)   [rad]
//   C(n) = kImplementations * kOpsPerInterface * (n + 1)
//
// u = 2^-53, the unit roundoff of IEEE double (round to nearest).
//
// L = length_scale(scene) = |display.z| + hypot(W, H) / 2 + D + t + max(|r1|, |r2| finite): a
//   length that bounds every coordinate and every intermediate length of the computation: the
//   vertices (|p| <= D + t), the display hit (<= hypot(W, H) / 2), the propagation distances
//   (<= |display.z| + D + t) and the sphere-centre offsets o - c of a face's intersection
//   (<= |R| + D + t; the cancellation in o - c costs u |R|, so |R| must be part of L).
//
// n = the number of interfaces (vertices) of the reference path; the "+ 1" is the final
//   propagation to the display plane, counted like an interface.
//
// kOpsPerInterface = 64. Standard forward error analysis (Higham, Accuracy and Stability of
//   Numerical Algorithms, 2nd ed., Sec. 3.1 and Lemma 3.1): a result computed through a chain of
//   k roundings has error <= gamma_k = k u / (1 - k u) ~ k u relative to the magnitude of the
//   operands (<= L for lengths, <= 1 for unit-vector components). The longest dependency chain of
//   one interface in AnalyticScene.cpp is ~44 roundings:
//     intersection (sphere; the quadric and cylinder are the same or shorter): o - c (1),
//       b = oc.d (3), w = oc - b d (2), |w| (4), (r - |w|)(r + |w|) (3), sqrt (1),
//       q = -(b + sgn sqrt) (1), c = (|oc| - r)(|oc| + r) (3), t = c / q (1), p = o + t d (2)
//       = 21;
//     normal (p - c) / r (2);
//     Snell: cos_i (3), d + cos_i n (2), sin^2 (3), eta^2 sin^2 (2), sqrt((1 - s)(1 + s)) (3),
//       eta cos_i - cos_t (2), eta d + k n (2), normalisation (5) = 22.
//   64 is the next power of two: the tracer's own formulation (a mesh hit refined onto the exact
//   surface, its own Snell code) is not known here and is allowed a comparable, not identical,
//   operation count. A local error made at interface i (<= 64 u L in position, <= 64 u in
//   direction) is, to first order, a perturbation of the ray leaving i; its effect downstream is
//   bounded by (1 + kappa) times its size, the 1 for an unmagnified error (e.g. at the last
//   interface) and kappa for a magnified one (assumption: the path magnifies a perturbation made
//   along the way no more than one made at its start; true for the lens and window paths checked
//   here, where every sub-path is itself a lens path). Summing over the n + 1 steps gives
//   64 (n + 1) u L (1 + kappa) per implementation.
//
// kImplementations = 2: the traced path and the reference path are two independent computations,
//   each within the bound of the exact path, so they differ by at most twice the bound.
//
// kappa = the path's sensitivity to its start, estimated by AnalyticScene::sensitivity with
//   central finite differences of the reference solver:
//     * the origin moved by +-h along the two unit vectors perpendicular to the direction,
//       h = kSensitivityRelativeStep * a (a = D/2: relative size 1e-7 of the object's aperture,
//       not of L, so that the near-rim rays at rho = a - 1e-6 a stay on their side of the rim);
//     * the direction turned by +-eta = kSensitivityRelativeStep rad about the same two axes
//       (an angle is already relative; its position effect is divided by L so that it reads
//       "per relative change", like u L is a relative change of a length L);
//   kappa = the largest |p(+) - p(-)| / (2 h) (resp. / (2 eta L)) over every vertex and the display
//   hit; kappa_dir = the largest |dir(+) - dir(-)| L / (2 h) (resp. / (2 eta)) of the final
//   direction. The finite-difference error is O(step) relative to kappa from truncation plus
//   ~u L / h ~ 1e-7 (rounding), both far below kappa's own meaning as an order of magnitude.
//   If a perturbed path has a different sequence of surfaces or events (the ray is within h of an
//   edge seam, a tangency or the critical angle), the ray is UNSTABLE: kappa = +inf and no
//   position tolerance is meaningful; validate must compare only what is discrete (the surface
//   sequence up to the instability) or report the ray as ill-conditioned, never pass it silently.
//
// C is not tuned to make anything pass: it is the count above.
#include <algorithm>
#include <cmath>
#include <limits>

#include "scene/Scene.h"
#include "validation/AnalyticScene.h"
#include "validation/ValidationRays.h"

namespace ltm::validation {

constexpr double kUnitRoundoff = 0x1p-53;          // u
constexpr double kOpsPerInterface = 64.0;          // roundings per interface, with margin (above)
constexpr double kImplementations = 2.0;           // tracer + reference
constexpr double kSensitivityRelativeStep = 1e-7;  // finite-difference step (relative)

// L: see above.
inline double length_scale(const Scene& scene) {
    const LensSpec& s = scene.object.lens;
    double r = 0;
    if (std::isfinite(s.r1)) r = std::max(r, std::fabs(s.r1));
    if (std::isfinite(s.r2)) r = std::max(r, std::fabs(s.r2));
    return std::fabs(scene.display.z) + 0.5 * std::hypot(scene.display.size[0], scene.display.size[1]) +
           s.diameter + s.center_thickness + r;
}

// C(n) for a path with n interfaces.
inline double tolerance_constant(int interfaces) {
    return kImplementations * kOpsPerInterface * (std::max(interfaces, 0) + 1);
}

// tol_pos (mm) for vertices and the display hit; +inf for an unstable ray (kappa = inf).
inline double position_tolerance(int interfaces, double L, double kappa) {
    return tolerance_constant(interfaces) * kUnitRoundoff * L * (1.0 + kappa);
}

// tol_dir (rad) for the final direction.
inline double direction_tolerance(int interfaces, double kappa_dir) {
    return tolerance_constant(interfaces) * kUnitRoundoff * (1.0 + kappa_dir);
}

// kappa of a validation ray (+inf if unstable).
inline double sensitivity(const AnalyticScene& scene, const ValidationRay& ray) {
    return scene.sensitivity(ray.origin, ray.direction).kappa;
}

// Both tolerances of one validation ray.
struct PathTolerance {
    double position = 0;   // mm
    double direction = 0;  // rad
    bool stable = true;    // false: see "UNSTABLE" above; position/direction are +inf
    RaySensitivity sensitivity;
};
inline PathTolerance path_tolerance(const AnalyticScene& scene, const ValidationRay& ray) {
    PathTolerance t;
    t.sensitivity = scene.sensitivity(ray.origin, ray.direction);
    t.stable = t.sensitivity.stable;
    const int n = t.sensitivity.interfaces;
    t.position = position_tolerance(n, scene.length_scale(), t.sensitivity.kappa);
    t.direction = direction_tolerance(n, t.sensitivity.kappa_dir);
    return t;
}

}  // namespace ltm::validation
