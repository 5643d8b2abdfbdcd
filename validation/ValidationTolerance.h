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
#include "validation/GrinReference.h"
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


// ---- graded-index (GRIN) paths: the tracer's closed forms against validation/GrinReference.h ----
//
// A GRIN path has n interfaces (vertices) and m CURVED segments (a segment, between two vertices
// or after the last one, that runs at least partly through a graded region). The tolerance is
//
//   tol_pos = (C_tracer + C_ref) u L (1 + kappa) + kReferenceSafety E_ref                  [mm]
//   C_tracer = kOpsPerInterface (n + 1) + m (kOpsPerCurvedSegment (1 + Phi) + kOpsPerRoot / c_min)
//   C_ref    = kOpsPerInterface (n + 1) + m kOpsPerReferenceRoot / c_min + kOpsPerStep N
//              + kOpsPerIncrement (S / L + P / n_min)
//
// with u, L, kappa and kOpsPerInterface as above (the two implementations are counted one by one
// here instead of kImplementations x one count: their curved segments are computed differently),
// and:
//
// C_tracer, the tracer's closed-form floor. Where n^2 is quadratic, r'' = (b + H r) / 2 has the
//   closed form r(tau) = r_c + sum over the eigenmodes of H of (a_i cos(w_i tau) + (v_i / w_i)
//   sin(w_i tau)) e_i (cosh / sinh for a positive eigenvalue, the polynomial r0 + p0 tau +
//   b tau^2 / 4 in a null mode), and a vertex is r(tau*) at the root tau* of the surface function
//   f(r(tau)) polished by Newton's method. Counting roundings as in the interface count above
//   (each relative to the magnitudes entering it, <= L for lengths):
//     evaluating r(tau*) and p(tau*): the frame change into the eigenbasis and back (two 3 x 3
//       products, 5 roundings each per component), per mode w tau (1), cos and sin (1 each, libm
//       within 1 ulp: 2 each), the products with a_i and v_i / w_i (3), the sum (1), the centre
//       r_c (1): ~20 for r and as many for p, ~40 in all, < kOpsPerCurvedSegment = 64;
//     the phase: the argument w tau carries the rounding of tau* and of the product, ~2 u |w tau|
//       relative, and sin, cos (or sinh, cosh: their derivatives are bounded by cosh) turn it
//       into an error ~2 u |w tau| times the amplitude (<= L): over a segment of phase
//       Phi = max |w tau| this adds ~2 Phi u L, covered by the factor (1 + Phi) on 64;
//     the root: Newton polishes tau* until f(r(tau*)) is at its rounding level, |f| <= ~8 u L
//       (the surface function's own evaluation, e.g. |r - c| - R, ~8 roundings of magnitude
//       <= L), so tau* is off the true root by |f| / |df/dtau| with df/dtau = grad f . p, i.e.
//       the vertex is off along the path by |f| / |cos i| <= 8 u L / c_min (|grad f| = 1, c_min
//       the smallest |cos| of incidence at a vertex ending a curved segment);
//       kOpsPerRoot = 16 gives 2x margin. This displacement runs ALONG the path, so it does not
//       perturb the ray downstream beyond the off-surface distance already counted; multiplying it
//       by (1 + kappa) anyway keeps the formula one product and only enlarges the bound.
//   The interface count 64 (n + 1) stays as before: the Snell step and the normal are the same
//   computation at a curved vertex, and the straight segments (air, homogeneous regions) are
//   exact quadric intersections as in the homogeneous case.
// C_ref, the GRIN reference's rounding (GrinReference.cpp), from its path's bookkeeping (GrinPath):
//   its interfaces and straight segments as AnalyticScene's, 64 (n + 1);
//   its roots, polished until the Newton correction is below 64 u scale / |df/dtau|: along the
//     path by <= 64 u L / c_min each, kOpsPerReferenceRoot = 64;
//   each of its N integration steps adds the step's increment to the state, one rounding of the
//     state's magnitude (<= L) per component, counted kOpsPerStep = 4 (position and momentum, x2);
//   the increments themselves: a Gragg midpoint sequence of n_j <= 16 substeps accumulates its
//     <= n_j + 4 roundings relative to the increment |Delta| (the scheme runs on increments), and
//     the Aitken-Neville extrapolation combines the 8 sequences with weights whose absolute sum is
//     the Lebesgue constant of extrapolating to 0 from the nodes 1 / n_j^2, n_j = 2, 4, .., 16:
//     119.03 (computed exactly in rationals), adding <= 8 roundings per column of its own, so an
//     increment carries <= 119 x 28 u |Delta| = 3332 u |Delta|; kOpsPerIncrement = 4096 leaves a
//     factor 1.2 for the flow's own growth within one step (a rounding error made within a step
//     grows by at most cosh(sqrt(lip) h) + sinh(sqrt(lip) h) / (sqrt(lip) h) < 1.2 by its end, lip
//     the Lipschitz constant of grad(n^2) / 2, since the reference limits every step to
//     sqrt(lip) h <= 1/2). Summed over the steps, the position
//     increments give S = integrated_length (mm), the momentum increments P = integrated_turn,
//     which turn the direction by <= P / n_min (n_min = min_index) and move the path by
//     <= L P / n_min: 4096 (S + L P / n_min) u, i.e. 4096 (S / L + P / n_min) in units of u L.
//   This is a worst-case count; the observed rounding of the reference is ~100x smaller.
// E_ref, the reference's truncation error, a posteriori (GrinReference::estimate_error): the GRIN
//   reference integrates the ray equation to a relative tolerance ~1e-12 of the object's size.
//   E_ref = |path(tol) - path(tol / 1000, half steps)| estimates the error of path(tol): the second
//   path's truncation error is ~1000x smaller, so |path(tol) - exact| <= E_ref (1 + 1e-3) plus
//   rounding (counted in C_ref; E_ref also samples it, the two paths' step sequences being
//   different). kReferenceSafety = 2 covers the estimate's own variation (the integration error is
//   not smooth in the tolerance: step sequences change discretely).
// Phi, c_min and m are read off the reference path (GrinPath: max_phase, min_cos_incidence,
// curved_segments; Phi uses the reference's phase_rate(), an upper bound of every |w_i|).
//
// Directions: the same with L = 1 and kappa_dir (the root's along-path error does not turn the
// direction, but the count is kept whole, as above):
//   tol_dir = (C_tracer + C_ref) u (1 + kappa_dir) + kReferenceSafety E_ref,dir.
//
// ---- TetGen-meshed fields (smooth inhomogeneities, linear_n): meshed_position_tolerance ----
//
// There the tracer does not follow the exact field but n~^2 = I(n^2), the linear interpolant of
// n^2 over each tetrahedron of the mesh (geometry/TetMesh.h), through which its paths are exact
// parabolas. The mesher refines until Waldron's bound M r^2 / 2 <= t (t = mesh.index_tolerance,
// M >= ||D^2 n^2|| over the tetrahedron's smallest enclosing ball of radius r), so the field error
// e = n~^2 - n^2 obeys |e| <= t everywhere. The path difference then comes from the field, not from
// rounding; a first-order bound (assumptions stated) follows.
//   The gradient of the error. On a tetrahedron with vertices x_i, barycentric coordinates
//   lambda_i and heights h_i (vertex i to the opposite face, |grad lambda_i| = 1 / h_i):
//   grad I f = sum_i f(x_i) grad lambda_i. Taylor at a point x of T, f(x_i) = f(x) + grad f(x) .
//   (x_i - x) + R_i with |R_i| <= M |x_i - x|^2 / 2 <= M (2 r)^2 / 2 = 2 M r^2 <= 4 t, and the
//   identities sum_i grad lambda_i = 0, sum_i (x_i - x) grad lambda_i^T = I (linear functions are
//   interpolated exactly) give grad I f(x) - grad f(x) = sum_i R_i grad lambda_i, so
//     |grad e| <= 4 t sum_i 1 / h_i =: G      (p1_gradient_error: 4 t q, q = max over the
//   tetrahedra the path crosses of sum_i 1 / h_i = (total face area) / (3 volume), tet_inverse_heights).
//   G is O(t / h_min): without a bound on the tetrahedra's shape (slivers) no bound in t alone
//   exists; for a shape-regular mesh refined to the criterion, h ~ sqrt(t / M) and G ~ sqrt(t M),
//   so the path error is O(sqrt t), not O(t), in the worst case over tetrahedra (the part of the
//   gradient error along the path integrates to a difference of e, O(t); the transverse part does
//   not).
//   The direction. In arclength, d/ds (n d) = grad n gives dd/ds = grad_perp n / n =
//   grad_perp(n^2) / (2 n^2) (perp: the part normal to d). Perturbing n^2 by e changes this by
//   grad_perp e / (2 n^2) - grad_perp(n^2) e / (2 n^4) to first order, of size at most
//   G / (2 n_min^2) + g t / (2 n_min^4), g = max |grad n^2| over the glass. Over the glass path of
//   length s the direction turns by at most s (G / 2 + g t / (2 n_min^2)) / n_min^2.
//   The interfaces. n at a vertex differs by |d sqrt(n^2)| <= t / (2 n_min); Snell
//   n1 sin i = n2 sin t' then turns the transmitted ray by (dn1 sin i - dn2 sin t') / (n2 cos t')
//   <= t / (n_min c_t) (both sides perturbed, n2 >= 1, c_t the smallest cosine of a transmitted
//   angle; total internal reflection does not depend on n). n interfaces: n t / (n_min c_t).
//   The position. A direction change eta anywhere along the path moves the later vertices and the
//   display hit by at most (1 + kappa) eta L: the assumption of the interface count above (a
//   sub-path magnifies no more than the whole path; the 1 for an unmagnified lever arm <= L).
//   Hence, to first order in t:
//     tol_mesh = (1 + kappa) L [s (G / 2 + g t / (2 n_min^2)) / n_min^2 + n t / (n_min c_t)]
//                + the GRIN tolerance above, with every tetrahedron crossed a curved segment of the
//                  tracer (a parabola: Phi = 0).
//   Second-order terms are O((s eta)^2): negligible while the bound itself is small compared to
//   the object (it is ~1e-4 of it for t = 1e-4); when it is not, the comparison is meaningless and
//   validate must say so rather than pass.

constexpr double kOpsPerCurvedSegment = 64.0;   // the tracer's closed-form r(tau), p(tau) at a root
constexpr double kOpsPerRoot = 16.0;            // the tracer's |f| at its polished root, in u L
constexpr double kOpsPerReferenceRoot = 64.0;   // the reference's root polish, in u L
constexpr double kOpsPerStep = 4.0;             // the reference's state update per step, in u L
constexpr double kOpsPerIncrement = 4096.0;     // the reference's increments, in u |Delta|
constexpr double kReferenceSafety = 2.0;        // factor on the GRIN reference's error estimate

// C_tracer for n interfaces, m curved segments (the tracer's own: for a closed-form field the
// reference's curved_segments), phase Phi and smallest incidence cosine c_min.
inline double grin_tracer_constant(int interfaces, int curved_segments, double max_phase, double min_cos_incidence) {
    const double m = std::max(curved_segments, 0);
    const double c = std::max(min_cos_incidence, std::numeric_limits<double>::min());
    return kOpsPerInterface * (std::max(interfaces, 0) + 1) +
           m * (kOpsPerCurvedSegment * (1.0 + max_phase) + kOpsPerRoot / c);
}

// C_ref of a reference path.
inline double grin_reference_constant(const GrinPath& ref, double L) {
    const int n = static_cast<int>(ref.path.vertices.size());
    const double c = std::max(ref.min_cos_incidence, std::numeric_limits<double>::min());
    const double nm = std::max(ref.min_index, std::numeric_limits<double>::min());
    return kOpsPerInterface * (n + 1) + ref.curved_segments * kOpsPerReferenceRoot / c + kOpsPerStep * ref.steps +
           kOpsPerIncrement * (ref.integrated_length / L + ref.integrated_turn / nm);
}

// tol_pos (mm) of a GRIN path: `ref` the reference's path (GrinReference::trace), L its length
// scale, kappa its sensitivity, reference_error = GrinReference::estimate_error(...).position.
inline double grin_position_tolerance(const GrinPath& ref, double L, double kappa, double reference_error) {
    const int n = static_cast<int>(ref.path.vertices.size());
    return (grin_tracer_constant(n, ref.curved_segments, ref.max_phase, ref.min_cos_incidence) +
            grin_reference_constant(ref, L)) *
               kUnitRoundoff * L * (1.0 + kappa) +
           kReferenceSafety * reference_error;
}

// tol_dir (rad) of a GRIN path; reference_error = GrinReference::estimate_error(...).direction.
inline double grin_direction_tolerance(const GrinPath& ref, double L, double kappa_dir, double reference_error) {
    const int n = static_cast<int>(ref.path.vertices.size());
    return (grin_tracer_constant(n, ref.curved_segments, ref.max_phase, ref.min_cos_incidence) +
            grin_reference_constant(ref, L)) *
               kUnitRoundoff * (1.0 + kappa_dir) +
           kReferenceSafety * reference_error;
}

// sum_i 1 / h_i of the tetrahedron (a, b, c, d): the face opposite vertex i has area A_i and
// V = A_i h_i / 3, so sum_i 1 / h_i = (A_0 + A_1 + A_2 + A_3) / (3 V) (1/mm).
inline double tet_inverse_heights(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    const double V = std::fabs(dot(b - a, cross(c - a, d - a))) / 6.0;
    const double area = 0.5 * (length(cross(c - b, d - b)) + length(cross(c - a, d - a)) +
                               length(cross(b - a, d - a)) + length(cross(b - a, c - a)));
    return area / (3.0 * V);
}

// G = 4 t q: the bound on |grad (I(n^2) - n^2)| for index tolerance t and q = the largest
// tet_inverse_heights over the tetrahedra the path crosses (above).
inline double p1_gradient_error(double index_tolerance, double inverse_heights) {
    return 4.0 * index_tolerance * inverse_heights;
}

// tol_mesh (mm), first order in the index tolerance t (above): `ref` the reference's path,
// `tetrahedra` the number of tetrahedra the traced path crossed, G = p1_gradient_error,
// s = the path's length in the meshed glass (mm), g = max |grad n^2| over the glass (1/mm),
// n_min = min n over the glass, c_t = the smallest cosine of a transmitted angle along the path.
inline double meshed_position_tolerance(const GrinPath& ref, int tetrahedra, double L, double kappa,
                                        double index_tolerance, double gradient_error, double glass_path_length,
                                        double max_grad_n2, double n_min, double min_cos_transmitted,
                                        double reference_error) {
    const double t = index_tolerance;
    const int n = static_cast<int>(ref.path.vertices.size());
    const double turn = glass_path_length * (0.5 * gradient_error + 0.5 * max_grad_n2 * t / (n_min * n_min)) /
                            (n_min * n_min) +
                        n * t / (n_min * std::max(min_cos_transmitted, std::numeric_limits<double>::min()));
    const double floor = (grin_tracer_constant(n, tetrahedra, 0.0, ref.min_cos_incidence) +
                          grin_reference_constant(ref, L)) *
                         kUnitRoundoff * L * (1.0 + kappa);
    return (1.0 + kappa) * L * turn + floor + kReferenceSafety * reference_error;
}

}  // namespace ltm::validation
