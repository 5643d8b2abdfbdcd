#pragma once
// An INDEPENDENT reference solver for light paths through graded-index (GRIN) glass: the
// numerical counterpart of AnalyticScene for objects whose index is a field n(x)
// (scene.object.index_field) and for index inhomogeneities (defects of type Inhomogeneity).
//
// Independence (as AnalyticScene.h): nothing of trace/ and none of geometry/Surface.h,
// geometry/Lens.h, geometry/Tessellate.h or geometry/IndexField.h's functions is included or
// called. The index field is read as plain data (IndexField's type, ior, gradient, g, hessian) and
// evaluated by this file's own code; the object's caps, rim and the defects' ellipsoids are this
// file's own quadrics. Only AnalyticScene's public interface optics (interact, the Fresnel
// equations), which are validation's own, and the plain data types are shared.
//
// The physics (derived in GrinReference.cpp): with the parameter tau, d tau = ds / n, and the
// momentum p = n dr/ds (so |p| = n), the ray equation d/ds (n dr/ds) = grad n becomes
//     dr/dtau = p,   dp/dtau = grad(n^2) / 2,
// a smooth autonomous system in (r, p). It is integrated by Gragg-Bulirsch-Stoer extrapolation
// (order 16) with adaptive steps; every surface that bounds the current medium is watched by a
// step classification that proves, before a step is taken, that the surface is either not crossed
// at all or crossed at most once within the step, so a crossing is located as a bracketed root
// of the surface function and can never be missed (GrinReference.cpp, "Event location").
// Inside homogeneous media (air, bubbles, glass whose field is uniform outside the smooth
// inhomogeneities, a uniform inclusion in uniform glass) the ray moves straight, intersected
// exactly with each quadric as in AnalyticScene.
//
// The object: as AnalyticScene (lens or window: caps on their sphere branch or plane, the rim
// cylinder between the edge heights), plus the ball (object type sphere, LensSpec{R, -R, 2R, 2R,
// ball = true}): the front cap is the hemisphere z <= 0, the back cap z >= 0, and the rim has no
// height (it is never hit). Absorbing rims and particles end a path (absorbed).
//
// Supported (grin_supports): a lens, window or ball with any index field kind; defects that are
// enclosed bubbles, absorbing particles and inhomogeneities (smooth or uniform), spheres or
// ellipsoids, pairwise disjoint. Scratches and surface-breaking bubbles are not modelled (their
// surfaces are the tracer's Boolean machinery, see AnalyticScene.h).
#include <memory>
#include <string>
#include <vector>

#include "geometry/Vec3.h"
#include "scene/Scene.h"
#include "validation/AnalyticScene.h"

namespace ltm::validation {

// True if the GRIN reference models the scene exactly; otherwise false, and *why (if given) names
// the offending key (e.g. "defects[2]") and the reason.
bool grin_supports(const Scene& scene, std::string* why = nullptr);

struct GrinOptions {
    // Local error per integration step, relative: positions to tolerance x object_size(),
    // momenta to tolerance x max(1, ior) (GrinReference.cpp, "Step-size control").
    double tolerance = 1e-12;
};

// The difference between two paths of the same ray (estimate_error).
struct PathError {
    double position = 0;     // mm: the largest vertex or display-hit difference
    double direction = 0;    // rad: the angle between the final directions
    bool comparable = true;  // false: the two paths met different surfaces or events (+inf above)
};

// A principal path with what the integration did to get it.
struct GrinPath {
    Path path;
    int steps = 0;                 // integration steps taken (accepted, rejected and event-locating)
    int curved_segments = 0;       // segments between consecutive vertices (or the end) that were
                                   // integrated, i.e. ran at least partly through a graded region
    double max_phase = 0;          // the largest omega tau over the curved segments (phase_rate())
    double min_cos_incidence = 1;  // the smallest |cos| of incidence at a vertex ending a curved
                                   // segment (1 if there is none)
    double integrated_length = 0;  // mm: the sum of |r(end) - r(start)| over the integration steps
    double integrated_turn = 0;    // the sum of |p(end) - p(start)| over the integration steps
    double min_index = 1;          // min(1, the smallest n = |p| at the integration's nodes): the
                                   // path starts in air
};

// Immutable after construction: every method is const and thread-safe.
class GrinReference {
public:
    static constexpr int kMaxInteractions = AnalyticScene::kMaxInteractions;
    // A path needing more integration steps than this is reported lost (never expected).
    static constexpr long kMaxSteps = 2'000'000;
    // estimate_error traces again at tolerance / kErrorEstimateRatio.
    static constexpr double kErrorEstimateRatio = 1000.0;

    // Throws std::invalid_argument (with the reason from grin_supports) for an unsupported scene
    // or a tolerance that is not in (0, 1).
    explicit GrinReference(const Scene& scene, const GrinOptions& options = {});

    const Scene& scene() const;
    double tolerance() const;
    double object_size() const;   // max(diameter, thickness): the scale of the position tolerance
    double length_scale() const;  // ValidationTolerance.h, length_scale(Scene)
    // omega = sqrt(||D^2 (n^2)|| / 2) (1/mm), an upper bound of the angular frequency of the
    // closed-form paths (n^2 quadratic: r'' = (b + H r) / 2 has modes cos(omega tau), cosh(omega tau)
    // with omega^2 = |eigenvalue of H| / 2); 0 for uniform glass and linear n^2.
    double phase_rate() const;

    // Surface ids: 0 front, 1 back, 2 rim, 3 + K for scene.defects[K].
    int surface_count() const;
    const std::string& surface_name(int id) const;

    // n at a point of the glass (inhomogeneities included; the uniform inclusions' delta_n inside
    // them), evaluated by this file's own code.
    double glass_index(const Vec3& x) const;

    // The deterministic principal path of a ray starting in air (throws std::invalid_argument if
    // the origin is inside the object): the transmitted branch at every interface, the reflected
    // one only under total internal reflection. The same Path as AnalyticScene::principal_path.
    Path principal_path(const Vec3& origin, const Vec3& direction) const;
    // The same with the integration's bookkeeping.
    GrinPath trace(const Vec3& origin, const Vec3& direction) const;

    // The reference's own error, a posteriori: the path traced at tolerance() against the path
    // traced at tolerance() / kErrorEstimateRatio with every step at most half as long (so its
    // truncation error is smaller by about that factor and its rounding is an independent sample,
    // its step sequence being different even where the event bounds, not the error, set the
    // steps): an estimate of the first path's truncation and rounding error.
    PathError estimate_error(const Vec3& origin, const Vec3& direction) const;

    // Finite-difference sensitivity of the path: the method of AnalyticScene::sensitivity
    // (ValidationTolerance.h), with this solver's paths.
    RaySensitivity sensitivity(const Vec3& origin, const Vec3& direction) const;

    struct Impl;

private:
    std::shared_ptr<const Impl> impl_;
};

}  // namespace ltm::validation
