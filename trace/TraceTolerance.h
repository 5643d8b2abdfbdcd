#pragma once
// Every numerical constant of the tracer, defined here and nowhere else, each with the analysis
// it comes from (the tracer's counterpart of validation/ValidationTolerance.h).
//
// Notation: u = 2^-53, the unit roundoff of double; uf = 2^-24, that of float (Embree works in
// float: ray origins and directions are rounded to float, and its hit distance is a float);
// L = the scene's length scale (the largest of the object's aperture, thickness and display
// distance, Tracer::scale); chord = the chord error of the faces of a tag (SolidBuilder.h).
//
// Which constants decide correctness and which only speed: the refined representation's hits
// are solved exactly on their analytic surfaces and the exact guard (Tracer.h) re-solves the glass
// boundary on every segment, so a candidate window that is too narrow only costs a spurious
// candidate or a guard hit (both counted in PathStats), never a wrong path. The spawn offsets, the
// guard's classification step and the GRIN root finder's bounds do decide correctness.
#include <cmath>
#include <limits>

namespace ltm::trace_tol {

inline constexpr double kU = std::numeric_limits<double>::epsilon() * 0.5;  // u = 2^-53
// Spacing of floats relative to their magnitude: 2 uf = 2^-23.
inline constexpr double kFloatUlp = 1.0 / (1 << 23);

// ---- Where a computed point is (Intersect.h, point_error_bound) ---------------------------------
// A root t of a quadric along o + t d is computed through ~20 roundings (the stable quadratic,
// ValidationTolerance.h counts them), each of at most u relative to the magnitudes involved: the
// point, the surface's origin and its radii (M = their sum). p = o + t d adds 2 more. Its distance
// from the surface is then at most |F(p)| (the exact residual, evaluated) plus the rounding of
// evaluating that residual, ~30 u M. 64 u M bounds both with a factor 2.
inline constexpr double kPointErrorUlps = 64.0;

// A spawned ray starts this many error bounds off the surface, on the side its new direction goes
// to: one bound puts the true point behind it, the second keeps the next root's own rounding
// (another bound of the same size) from putting the surface just left ahead of it again.
inline constexpr double kSpawnOffsetBounds = 2.0;

// Below this |cos| between the new direction and the normal, stepping along the direction by
// offset / |cos| would move the ray by more than 1000 offsets: such near-tangent rays are moved
// along the normal instead (which shifts the path sideways by one offset, ~1e-13 L).
inline constexpr double kSpawnMinCos = 1e-3;

// ---- Culling a patch before solving it (Patch::cull, Tracer::analytic_hit, exact_guard) ------------
// A patch is solved only if the segment meets its box inflated by kCullMargin x (its extent +
// its largest coordinate). Every root patch_hit accepts lies on the patch up to its boundary
// slack (8 u of the aperture) and the rounding of o + t d (a few u (|o| + t)), both ~1e-14 of the
// scene, and the slab test's own rounding is of the same size; 1e-9 is 5 orders above them, so
// the cull never drops a root the solve would have returned (results are bit-identical with and
// without it) and still rejects every patch the segment misses by more than ~1e-8 mm.
inline constexpr double kCullMargin = 1e-9;
// The rim (a cylinder of radius a) is not solved for a segment whose both ends lie inside it by
// kRimInsideMargin a in radius: the set inside a cylinder is convex, so the segment cannot cross
// it, and its line passes the axis within a (1 - m), so the quadratic's discriminant is at least
// ~2 m a^2 and its computed roots err by ~u a / sqrt(2 m) ~ 1.6e-13 a for m = 1e-6, far less than
// their distance m a from the ends: no root the solve would return lies in the segment.
inline constexpr double kRimInsideMargin = 1e-6;

// ---- The exact guard (Tracer::exact_guard, Tracer::on_glass_boundary) ------------------------------
// A root of a cutter's surface is a crossing of the glass boundary where membership of the cutter
// changes across it; membership is tested at t -+ delta along the ray. delta must exceed the
// root's error along the ray (~kPointErrorUlps u L / cos(incidence), and more for a grazing ray)
// and stay below the smallest feature a scene can hold (the thinnest groove a test uses is 1e-3 mm
// at L ~ 10 mm, 1e-4 L), and near a corner of a tool's profile (a U's side line meeting its bottom
// arc, a V's apex) it must stay below the distance to the corner, or the test sees the other wall.
// So delta = kGuardStepBounds x the root's point error bound (kSpawnOffsetBounds x
// point_error_bound) / cos, a factor 4 above the error, floored at kPointErrorUlps u (|t| + L);
// where that exceeds kGuardStepMax (|t| + L) = 1e-9 L (grazing roots), delta is that: 4 orders of
// magnitude inside both the error and the smallest feature. (With 1e-9 L for every root, rays
// within it of such corners would refract at a wall's continuation; tests/trace_stress.cpp shoots
// such rays.)
// A wall's root counts only inside the lens, up to the rounding of the root and of the lens's
// distance: kSpawnOffsetBounds x its point error bound.
inline constexpr double kGuardStepBounds = 4.0;
inline constexpr double kGuardStepMax = 1e-9;

// ---- Embree candidates (Tracer::next_hit_refined) ------------------------------------------------
// A candidate's float distance differs from the true facet distance by the float rounding of the
// ray (origin and direction, uf each) and of Embree's own arithmetic (a handful of float
// operations): 16 float ulps of (|o| + t) cover ~8 roundings with a factor 2. The facet itself is
// within chord of its surface, i.e. chord / |cos| along the ray, doubled for the facet on either
// side; |cos| is floored at kCandidateMinCos (grazing facets: the guard has the last word).
inline constexpr double kCandidateFloatUlps = 16.0;
inline constexpr double kCandidateMinCos = 1e-3;
// A rejected candidate is stepped past by 4 float ulps of (|o| + t): beyond its own rounding.
inline constexpr double kCandidateStepUlps = 4.0;
// A ray that slipped through a mesh vertex is re-queried with its origin moved by
// kJitterUlps x attempt float ulps of |o| sideways (in a new direction each time, the golden
// angle), far enough for float rounding to send it through a face instead; up to kLeakRetries
// attempts, then the leak is counted (PathStats::leaks_unresolved).
inline constexpr double kJitterUlps = 16.0;
inline constexpr int kLeakRetries = 6;
inline constexpr double kGoldenAngle = 2.399963229728653;
// Origins are measured against max(|o|, kOriginFloor L), so a ray from near the origin still
// gets a jitter that float rounding can see at the scene's scale.
inline constexpr double kOriginFloor = 1e-3;
// The facet just left is skipped while it can still lie ahead of the spawned ray: within the
// band of width 2 chord around the surface, doubled, plus 64 float ulps of L, over |cos|.
inline constexpr double kSkipChords = 4.0;
inline constexpr double kSkipFloatUlps = 64.0;
// Mesh-only hits are Embree's float points: 8 float ulps of their magnitude off the facet.
inline constexpr double kMeshOnlyOffsetUlps = 8.0;

// ---- Graded-index paths (GrinPath.h) -------------------------------------------------------------
// The guaranteed stepping never skips a root; near an exact tangency its steps shrink without
// bound, so they are floored at kGrinMinStep x (the object's radius / n_max) in tau: a pair of
// crossings closer than that (a chord of ~1e-13 of the object) is below the rounding of the
// positions themselves and is treated as a touch.
inline constexpr double kGrinMinStep = 1e-13;
// A path in the glass crosses its boundary; the steps to a crossing grow geometrically away
// from a surface, so a few dozen suffice (measured: < 40 on grazing rays); 10^4 only stops a
// path that is trapped by a field (never for the valid fields, whose rays all exit).
inline constexpr int kGrinMaxSteps = 10000;
// A periodic (trigonometric) path that has not met a surface's patch within this many periods
// never will in practice (its crossings repeat every period); it is then trapped, and lost.
inline constexpr int kGrinMaxPeriods = 64;
// The invariant |p|^2 = n^2(r) at a segment's end: both sides are evaluated through ~40
// roundings of quantities of size n_max^2 (the closed form's trigonometric sums, the quadratic
// form), so they agree to 64 u n_max^2 per segment; a path is checked against 1e6 times that
// (1e-8 relative), far above rounding, far below any physical effect: a violation is a bug.
inline constexpr double kHamiltonianRelative = 1e-8;

// ---- Tetrahedral walks (TetWalk.h) ----------------------------------------------------------------
// A walk makes at most this many zero-length steps in a row (a path through an edge or a vertex
// passes through every tetrahedron around it, each at tau = 0) before it is stopped as stuck;
// the largest vertex star of a TetGen quality mesh holds < 100 tetrahedra.
inline constexpr int kWalkMaxZeroSteps = 256;
// Tetrahedra per segment before a walk is stopped: a path crosses a region of diameter D with
// tetrahedra of size h in ~ D / h steps; 10^7 exceeds any mesh the tolerance allows.
inline constexpr long kWalkMaxSteps = 10'000'000;
// Point location accepts barycentric coordinates down to -kLocateSlack (a point on a shared
// face or just outside the covering region by rounding).
inline constexpr double kLocateSlack = 1e-12;

}  // namespace ltm::trace_tol
