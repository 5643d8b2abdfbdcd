#pragma once
// An INDEPENDENT analytic reference solver for the light paths of a scene.
//
// This is the "textbook side" of `ltmsim validate`: every formula here is derived from first
// principles in AnalyticScene.cpp (the derivations are in the comments there) and nothing is
// shared with the tracer: no file of trace/ and none of geometry/Surface.h, geometry/Lens.h or
// geometry/Tessellate.h is included or called. Only the plain data types (geometry/Vec3.h,
// scene/Scene.h) are shared, so an error in the tracer's geometry or optics cannot be repeated
// here and go unnoticed.
//
// The object (docs/conventions.md): centred at the origin, front vertex at z = -t/2, back vertex
// at z = +t/2, radii with the optics sign convention (R > 0: centre of curvature at +z of the
// vertex; inf: a plane), a cylindrical rim rho = D/2 between the caps' edges. The solid is
//     { rho <= a, z_front(rho) <= z <= z_back(rho) },  a = D/2,
//     z_front(rho) = -t/2 + sag(r1, rho),  z_back(rho) = +t/2 + sag(r2, rho),
//     sag(R, rho) = R - sgn(R) sqrt(R^2 - rho^2)   (0 for a plane).
// Glass has index scene.object.lens.ior, air (outside and in the bubbles) has index 1.
//
// Supported defects (see `supports`): enclosed air bubbles and absorbing particles, spheres or
// rotated ellipsoids (both are quadrics, intersected exactly), pairwise disjoint. Surface-breaking
// bubbles (pits) and scratches are not modelled: their surfaces (trimmed spheres, cones, tori) are
// exactly what the tracer's Boolean machinery produces and would have to be re-implemented here.
#include <functional>
#include <string>
#include <vector>

#include "geometry/Vec3.h"
#include "scene/Scene.h"

namespace ltm::validation {

// True if the analytic solver models the scene exactly: a lens or window whose defects are only
// enclosed bubbles and absorbing particles (spheres or ellipsoids) that do not overlap each other.
// Otherwise false, and *why (if given) names the first defect that is not supported and the reason.
bool supports(const Scene& scene, std::string* why = nullptr);

// ---- interface optics (derived in AnalyticScene.cpp) --------------------------------------------

// Fresnel coefficients for light going from index n1 into index n2 at incidence cosine cos_i in
// [0, 1]. Amplitude coefficients (Hecht, Optics, Sec. 4.6.2):
//   rs = (n1 ci - n2 ct) / (n1 ci + n2 ct),  rp = (n2 ci - n1 ct) / (n2 ci + n1 ct),
//   ts = 2 n1 ci / (n1 ci + n2 ct),          tp = 2 n1 ci / (n2 ci + n1 ct),
// power coefficients Rs = rs^2, Rp = rp^2, Ts = (n2 ct / n1 ci) ts^2, Tp = (n2 ct / n1 ci) tp^2,
// unpolarised R = (Rs + Rp) / 2, T = (Ts + Tp) / 2. Under total internal reflection
// (n1 sin_i > n2) R = Rs = Rp = 1, T = 0 and cos_t = 0.
struct Fresnel {
    bool tir = false;
    double cos_t = 0;  // cosine of the refraction angle (0 under TIR)
    double Rs = 1, Rp = 1, R = 1;
    double Ts = 0, Tp = 0, T = 0;  // from the transmission amplitudes, independently of R
};
Fresnel fresnel(double n1, double n2, double cos_i);

// The interaction of a unit direction d with an interface of unit normal `normal` (either
// orientation) between index n1 (the side d comes from) and n2: the refracted direction by the
// vector form of Snell's law, or the mirror direction under total internal reflection.
struct Interaction {
    Vec3 direction;        // refracted (tir == false) or reflected (tir == true), unit
    Vec3 reflected;        // the mirror direction (always computed), unit
    Vec3 normal;           // the normal oriented against d: dot(normal, d) <= 0
    bool tir = false;
    double cos_i = 1, cos_t = 1;
    double R = 0;          // unpolarised Fresnel reflectance (1 under TIR)
};
Interaction interact(const Vec3& d, const Vec3& normal, double n1, double n2);

// Mirror reflection of d about the plane with unit normal n: d - 2 (d.n) n.
Vec3 reflect(const Vec3& d, const Vec3& n);

// ---- the scene ----------------------------------------------------------------------------------

enum class MediumKind { Air, Glass, Bubble, Particle };
struct Medium {
    MediumKind kind = MediumKind::Air;
    int defect = -1;  // index into scene.defects for Bubble / Particle
    bool operator==(const Medium& o) const { return kind == o.kind && defect == o.defect; }
    bool operator!=(const Medium& o) const { return !(*this == o); }
};

// What happened at one vertex of a path.
enum class Event { Transmitted, TotalInternalReflection, Absorbed };

struct Path {
    std::vector<Vec3> vertices;         // interface hits in order (the absorbing hit included)
    std::vector<std::string> surfaces;  // "front", "back", "rim", "bubble K", "particle K"
                                        // (K = index of the defect in scene.defects)
    Vec3 direction;                     // final unit direction (the incoming one if absorbed)
    bool absorbed = false;              // ended on a particle or an absorbing rim
    bool truncated = false;             // stopped after kMaxInteractions interactions
    bool lost = false;                  // found no exit from a closed medium (never expected)
    bool display_hit = false;           // reached the display plane (dz > 0, not absorbed,
                                        // not truncated or lost)
    double display_x = 0, display_y = 0;  // where it meets the plane z = display.z
    bool on_display = false;            // |x| <= W/2 and |y| <= H/2
    int display_p = -1, display_q = -1; // pixel (row from +y down, column from -x); -1 if off
    double transmission = 1;            // product of (1 - R) over the transmitted interfaces
    int tir_count = 0;
    // Extras for checks: per vertex, the event, the surface id and the unit direction leaving it.
    std::vector<Event> events;
    std::vector<int> surface_ids;
    std::vector<Vec3> directions;
};

// One exact ray-surface intersection.
struct SurfaceHit {
    bool hit = false;
    double t = 0;      // ray parameter (the direction need not be unit: point = o + t d)
    Vec3 point;
    Vec3 normal;       // unit geometric normal of the surface (not oriented against the ray)
    int surface = -1;  // surface id (see AnalyticScene::surface_name)
};

// Sensitivity of a ray's path to its start (see validation/ValidationTolerance.h).
struct RaySensitivity {
    double kappa = 0;       // |d position| / |d start| (vertices and display hit), dimensionless
    double kappa_dir = 0;   // |d final direction| per relative change of the start
    bool stable = true;     // false: a perturbation changed the sequence of surfaces or events
    int interfaces = 0;     // number of vertices of the nominal path
};

// Immutable after construction: every method is const and thread-safe.
class AnalyticScene {
public:
    static constexpr int kMaxInteractions = 1000;

    // Throws std::invalid_argument (with the reason from `supports`) for an unsupported scene.
    explicit AnalyticScene(const Scene& scene);

    const Scene& scene() const { return scene_; }
    double ior() const { return n_glass_; }
    double aperture_radius() const { return a_; }
    double thickness() const { return t_; }
    double z_front(double rho) const;   // the front face's z at radial distance rho <= a
    double z_back(double rho) const;
    double z_min() const { return z_min_; }  // the object's extent along z
    double z_max() const { return z_max_; }
    double length_scale() const { return L_; }  // ValidationTolerance.h, length_scale(Scene)

    // Surface ids: 0 front, 1 back, 2 rim, 3 + K for scene.defects[K].
    int surface_count() const { return static_cast<int>(surfaces_.size()); }
    const std::string& surface_name(int id) const { return surfaces_.at(id).name; }

    // The medium at point p (boundaries belong to the outer medium).
    Medium medium_at(const Vec3& p) const;
    // The medium on the other side of surface `id` for a ray currently in `from`.
    Medium across(int id, const Medium& from) const;

    // The nearest exact hit with t > 0 of the ray o + t d (d need not be unit) among the surfaces
    // bounding medium `in`. `last` is the surface the ray starts on (-1: none): its root at the
    // origin is excluded exactly (the other root of its quadratic is used instead).
    SurfaceHit first_hit(const Vec3& o, const Vec3& d, const Medium& in, int last = -1) const;
    // The nearest exact hit (t > 0, on the surface's patch) of the single surface `id`, whatever
    // the medium; starts_on as for `last` above.
    SurfaceHit hit_one(int id, const Vec3& o, const Vec3& d, bool starts_on = false) const;

    // The deterministic principal path of a ray starting in air (throws std::invalid_argument if
    // the origin is not in air): the transmitted branch at every interface, the reflected one
    // only under total internal reflection.
    Path principal_path(const Vec3& origin, const Vec3& direction) const;
    // The same from a given medium (for rays constructed inside the glass, e.g. in tests);
    // `start_surface` as `last` in first_hit.
    Path principal_path(const Vec3& origin, const Vec3& direction, const Medium& start,
                        int start_surface = -1) const;

    // The exact expectation, over the full Fresnel branching tree (reflected branch weight R,
    // transmitted 1 - R, TIR weight 1), of the probability that a ray from `origin` (in air)
    // ends on the display (|x| <= W/2, |y| <= H/2, dz > 0, not absorbed). Branches lighter than
    // `cutoff` or with more than `max_depth` interactions are dropped; their total weight is
    // stored in *dropped_weight (if given), so the true value lies in [result, result + dropped].
    // Light trapped by total internal reflection (a skew ray circling between the faces and a
    // polished rim) is dropped after max_depth interactions, so it is counted there as well.
    double expected_display_throughput(const Vec3& origin, const Vec3& direction,
                                       int max_depth = 64, double cutoff = 1e-14,
                                       double* dropped_weight = nullptr) const;

    // The moments of one camera sample's value X (the total weight its branches bring to the
    // display) under the split estimator (scene/Scene.h, Estimator::Split) with `split_depth`,
    // for a ray from `origin` in air. The first split_depth Fresnel interactions of every branch
    // (TIR is none) are followed both ways with weights R and 1 - R; a branch with no split left
    // (a "root", weight w) goes on as a sampled path: it reaches the display with probability
    // tau_r (its whole Fresnel tree, as expected_display_throughput) and then brings w, else 0.
    // Roots draw independent random numbers, so
    //   E[X] = sum_r w_r tau_r + (deterministic leaves on the display),
    //   Var[X] = sum_r w_r^2 tau_r (1 - tau_r).
    // split_depth = 0: the one root is the ray itself, E = tau, Var = tau (1 - tau) (the sample
    // estimator with weight 1). `dropped` as for expected_display_throughput.
    struct SplitMoments {
        double mean = 0, variance = 0, dropped = 0;
    };
    SplitMoments split_sample_moments(const Vec3& origin, const Vec3& direction, int split_depth,
                                      int max_depth = 64, double cutoff = 1e-14) const;

    // Finite-difference sensitivity of the path (ValidationTolerance.h documents the method).
    RaySensitivity sensitivity(const Vec3& origin, const Vec3& direction) const;

private:
    enum class Kind { SphereCap, PlaneCap, Rim, Ellipsoid };
    struct Surf {
        Kind kind;
        std::string name;
        int defect = -1;      // for Ellipsoid
        bool particle = false;
        // SphereCap: centre, |R|, sign of R (branch through the vertex: sgn(R) (z - zc) <= 0).
        // PlaneCap: z0. Ellipsoid: centre, M = S^-1 R^T (world offset -> unit-sphere body
        // coordinates), sphere radius if the defect is a sphere (exact sphere formulas).
        Vec3 center;
        double radius = 0;
        double sign = 1;
        double z0 = 0;
        Mat3 M;
        bool is_sphere = false;
    };

    bool hit_surface(const Surf& s, int id, const Vec3& o, const Vec3& d, bool starts_on,
                     double tmin, SurfaceHit& out) const;
    bool on_patch(const Surf& s, const Vec3& p) const;
    Vec3 normal_at(const Surf& s, const Vec3& p) const;
    void finish_display(Path& path, const Vec3& o) const;

    // A branch of the Fresnel tree: where it starts, in which medium, after which surface, after
    // how many interactions, with which weight, and how many of its interactions are still split.
    struct Branch {
        Vec3 o, d;
        Medium m;
        int last;
        int depth;
        double w;
        int splits;
    };
    // Walks the tree below `start` depth first and returns the weight that ends on the display.
    // With `root`, a branch with no split left is handed to it instead of being walked; without,
    // `splits` is ignored and every branch is walked. Dropped weight is added to `dropped`.
    double walk_fresnel_tree(const Branch& start, int max_depth, double cutoff, double& dropped,
                             const std::function<void(const Branch&)>* root) const;

    Scene scene_;
    double n_glass_ = 1.5, a_ = 1, t_ = 1, r1_ = 0, r2_ = 0;
    double z_edge_front_ = 0, z_edge_back_ = 0, z_min_ = 0, z_max_ = 0, L_ = 1;
    double tmin_ = 0;
    bool absorbing_rim_ = false;
    std::vector<Surf> surfaces_;
};

}  // namespace ltm::validation
