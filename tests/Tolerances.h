#pragma once
// Every numerical tolerance the tests use, in one place, each with its derivation. A tolerance
// here is never loosened to make a test pass; a failing test means the code or the derivation is
// wrong.
#include <cmath>
#include <limits>

namespace ltm::tol {

constexpr double kEps = std::numeric_limits<double>::epsilon();  // 2.22e-16

// A vertex computed as (rho cos phi, rho sin phi, z(rho)) from O(1) double operations is off its
// analytic surface by a few ulps of the coordinates' magnitude L: |f(p)| <= 16 eps L covers the
// ~8 rounded operations of the sag / trig evaluation with a factor-2 margin.
inline double on_surface(double scale) { return 16.0 * kEps * scale; }

// Volume of a tessellated solid vs its analytic volume: every face lies within the chord error e
// of its surface, so the region between mesh and surface has volume at most e x area. The bound
// is summed over the object's surfaces (e_obj x A_obj) and the defect tools (e_k x A_k).
inline double volume_bound(double object_error, double object_area, double defect_error_area_sum) {
    return object_error * object_area + defect_error_area_sum;
}

// Face-on-surface check after a Boolean: corefinement vertices are exact intersections of two
// facets, each within its chord error e of its surface, so a face can be at most max(e_host,
// e_tool) from its tagged surface, plus the final rounding of exact coordinates to double
// (relative eps, doubled for the distance evaluation).
inline double face_on_surface(double chord_error, double scale) { return chord_error + 4.0 * kEps * scale; }

// cos_sin_turns(u) against cos(2 pi u) and sin(2 pi u) (trace/SinCos.h derives it): the quarter
// turns are exact, the reduced angle x = (pi / 2) r (|x| <= pi / 4) carries two roundings (the
// product and pi / 2's own), at most 2 (eps / 2) |x| <= 0.79 eps of angle, and fdlibm's kernels
// add their approximation error (2^-58) and under an ulp of evaluation: 0.79 + 0.5 + 0.03 below
// 1.5 eps; 1.5 eps = 3 x 2^-53 in absolute terms, both results being at most 1.
constexpr double kTurnCosSin = 1.5 * kEps;

// app_mesh_command: MeshLab 2020.09's "Mesh Volume" of an exported mesh against the mesh's own
// signed volume V. MeshLab holds coordinates as float (CMeshO) and integrates the volume with
// Mirtich's algorithm (vcg/complex/algorithms/inertia.h) in double from those floats, each face's
// plane given by its float unit normal through its first vertex; it returns a float, printed
// with 6 decimals. With u = 2^-24 (float's unit roundoff), L the largest |coordinate|, A the area:
//  - rounding each coordinate to float moves a vertex by at most sqrt(3) u L, so the surface
//    sweeps at most sqrt(3) u L A of volume;
//  - a face's float unit normal (edges of length <= d, area a, so |e1 x e2| = 2a) is off by at
//    most 3 u d^2 / (2a) (each component of the cross product within 3 u |e1| |e2| <= 3 u d^2)
//    plus 2 u (the normalisation); the plane through the first vertex then tilts by at most
//    sqrt(3) |dn| d over the face (Mirtich solves for the normal's largest component,
//    |n_C| >= 1/sqrt(3)): at most sqrt(3) u (1.5 d^3 + 2 a d) of volume per face;
//  - the float result, u |V|; the printing, 5e-7; the double integration (~1e-16 relative) is
//    far below these.
// `face_terms` is the sum over faces of 1.5 d^3 + 2 a d. The bound is doubled for the second-order
// terms and the float differences of the edges (relative u each).
inline double meshlab_volume(double volume, double scale, double area, double face_terms) {
    return 2.0 * (std::ldexp(std::fabs(volume) + std::sqrt(3.0) * (scale * area + face_terms), -24) + 5e-7);
}

// Rec. 709 luminance of a float RGB pixel (io/Image.h, pattern_values): the code evaluates
// Y = 0.2126 R + 0.7152 G + 0.0722 B in double and rounds to float. With S = 0.2126|R| +
// 0.7152|G| + 0.0722|B|, the double evaluation (3 rounded weights, 3 products, 2 sums) is within
// 8 * 2^-53 S of the exact value and the final rounding to float adds at most 2^-24 |Y| <= 2^-24 S;
// a reference computed the same way in double has the same 8 * 2^-53 S. Their difference is below
// 2^-24 S + 16 * 2^-53 S < 2^-23 S.
inline double luminance(double weighted_abs_sum) { return std::ldexp(weighted_abs_sum, -23); }

// ---- validation_analytic: the analytic reference solver (validation/) against closed forms ----

// Fresnel coefficients and single-interface identities (R + T = 1, R at normal incidence, the
// mirror direction under TIR): each quantity is ~10 rounded operations from the cosines
// (numerator, denominator, quotient, square, average), each contributing at most u = eps / 2
// relative to O(1) magnitudes, and the closed form compared against ~5 more: 15 u < 8 eps; 16 eps
// leaves a factor 2.
inline double optics_identity() { return 16.0 * kEps; }

// Snell's law n1 sin_i = n2 sin_t as an identity on computed vectors: the refracted direction
// carries the ~22 roundings of the Snell step (validation/ValidationTolerance.h counts them) and
// each sine |v x N| ~6 more: ~30 u relative to the O(n) terms, < 16 eps n; 32 eps n with margin.
inline double snell_identity(double n) { return 32.0 * kEps * n; }

// A path of the analytic solver against a closed-form path (window displacement, undeviated
// diameter rays): the solver's own bound 64 (n + 1) u L (1 + kappa) from ValidationTolerance.h
// for one implementation (n interfaces, L = its length scale, kappa = its sensitivity), plus one
// more "interface" of 64 u L (1 + kappa) for the closed form evaluated in double (a handful of
// trigonometric and arithmetic operations, < 64): 64 (n + 2) u L (1 + kappa). Directions: the
// same with L = 1 and kappa_dir.
inline double closed_form_path(int interfaces, double scale, double kappa) {
    return 64.0 * (interfaces + 2) * (kEps / 2) * scale * (1.0 + kappa);
}

// Paraxial focus of a thick lens measured with one real ray at height h: the ray crosses the axis
// short of the paraxial focus by its longitudinal spherical aberration, to third order
// LA = c3 h^2 / f (thin-lens Seidel result, object at infinity, Hecht, Optics, 4th ed., Sec. 6.3.1:
// c3 = [(n+2)/(n-1) q^2 + 4(n+1) p q + (3n+2)(n-1) p^2 + n^3/(n-1)] / (8 n (n-1)), q the shape
// and p the position factor). Relative to f that is c3 (h/f)^2; the bound 2 c3 (h/f)^2 allows the
// thick-lens correction of the coefficient (O(t/f) ~ 0.1 for the lenses tested) and the fifth
// order (a further factor (h/f)^2 ~ 1e-7). Rounding (~64 u L / h relative to the measured
// distance, ~1e-9 for h = 0.01 mm) is far below it.
inline double paraxial_focus_relative(double c3, double h, double f) { return 2.0 * c3 * (h / f) * (h / f); }
// ... and the shortfall is O(h^2): doubling h multiplies it by 4 up to the fifth-order term (a
// relative change ~(2h/f)^2 ~ 1e-7) and rounding (the shortfall, ~6e-8 f, is measured to ~1e-12 f:
// ~2e-5 relative); 1e-3 relative on the ratio 4 leaves a factor 50.
inline double paraxial_scaling() { return 1e-3; }

// The Fresnel branching tree summed by expected_display_throughput against the closed geometric
// series T^2 / (1 - R^2) (or a stack of them): up to a few thousand retained terms, each a product
// of <= 64 factors (<= 64 u relative) and summed (<= 1e4 u relative to the total): < 1e-12 / 1000;
// the dropped branches are reported separately (their total is asserted to be small too, with a
// cutoff fine enough for the case). 1e-12 leaves a factor 100 over the rounding.
inline double throughput_series() { return 1e-12; }

}  // namespace ltm::tol

namespace ltm::tol {

// ---- trace_split: the split estimator's deterministic branches against closed forms ----

// A defect-free window at exact normal incidence: every deterministic branch weight is a product
// of at most `depth` Fresnel factors (R or T = 1 - R) computed by trace/Optics.h, and the closed
// form multiplies the same number of factors from R = ((n - 1) / (n + 1))^2. Each factor differs
// between the two by at most ~8 u relative (the tracer: eta = n1 / n2 (1 rounding), eta cos_i -
// cos_t and eta cos_i + cos_t (exact or 1 rounding each at cos_i = cos_t = 1), the quotient, the
// square, the average of rs^2 and rp^2: ~6 u; the closed form ~3 u; T = 1 - R is better than R
// relative since R < 1/2), each product adds 1 u per factor, and the sum of the floor(depth/2)
// ghosts 1 u per term: (8 + 1) depth + depth / 2 < 10 (depth + 2) u, relative to the sum of
// positive terms; 16 (depth + 2) u leaves a factor 1.6.
inline double split_exact_relative(int depth) { return 16.0 * (depth + 2) * (kEps / 2); }

}  // namespace ltm::tol

namespace ltm::tol {

// Two-sided normal quantile z with P(|Z| > z) = p, by bisection on erfc (exact to ~1e-12).
inline double normal_two_sided_quantile(double p) {
    double lo = 0, hi = 40;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (std::erfc(mid / std::sqrt(2.0)) > p) lo = mid; else hi = mid;
    }
    return 0.5 * (lo + hi);
}

// Per-pixel Z-tests of a Monte Carlo image: the family-wise false-alarm rate is kept at
// kFamilyAlpha by Bonferroni's correction, i.e. each of the `pixels` tests uses alpha / pixels.
constexpr double kFamilyAlpha = 1e-4;
inline double bonferroni_z(long pixels) { return normal_two_sided_quantile(kFamilyAlpha / static_cast<double>(pixels)); }

}  // namespace ltm::tol

namespace ltm::tol {

// ---- app_*: the command line's outputs ----

// Row sums of a rendered T (ltm.npz): T[k, l] = float(W_l / n), W_l the summed weights of the
// pixel's n samples that landed on display pixel l. Every weight is 1 unless Russian roulette
// (from the 64th interaction on, trace/Tracer.h) let a path survive with weight 1 / 0.9: in the
// small scenes of the app tests no path comes near 64 interactions, so the exact row sum is a
// count / n <= 1. Rounding each entry to float32 adds at most 2^-24 relative per entry, i.e.
// 2^-24 x (row sum) <= 6e-8 in total, and summing <= n entries in double adds n u ~ 1e-15:
// 1e-6 leaves a factor 16.
inline double ltm_row_sum_slack() { return 1e-6; }

// `render --pattern` against T x from a plain render with the same seed: both trace the same
// samples, so they differ only by rounding. With S = sum_l |T[k, l] x_l| and y the stored value:
//   T[k, l] = (W_l / n)(1 + e_l), |e_l| <= 2^-24 (float32 storage of T);
//   the test's x_l = c / 255 rounded to float and the reader's (v / 255 scaled to [0, 1], maybe
//   rounded through double) differ by at most one float ulp, 2^-23 relative;
//   y = (sum_s w_s x_{l_s}) / n in double (<= n u relative, n <= 1024: < 2^-42), stored as
//   float32 (2^-24 |y|); T x accumulated in double (nnz u relative, negligible likewise).
// So |T x - y| <= (2^-24 + 2^-23) S + 2^-24 |y| + 2^-41 S < 2^-22 (S + |y|).
inline double pattern_identity(double S, double y_abs) { return std::ldexp(S + y_abs, -22); }

// One exact ray-surface intersection computed in double: validation/ValidationTolerance.h counts
// <= 64 roundings per interface (intersection, normal, Snell), each relative to the magnitudes
// entering it; for a sphere of radius R hit from origin o these are bounded by M = |o - c| + R.
// A vertex is therefore within 64 u M (u = eps / 2) of the exact intersection of the line it was
// computed for. Used for rays along the optical axis of a lens: by symmetry the line stays the
// axis whatever the rounding of earlier vertices (an error along the ray does not move the line),
// so each axial vertex carries only its own intersection's rounding.
inline double single_intersection(double magnitude) { return 64.0 * (kEps / 2) * magnitude; }

}  // namespace ltm::tol

namespace ltm::tol {

// ---- features_rows: row features of T (features/Features.h) against a direct reference ----
// u = eps / 2 = 2^-53 below; the test's references are evaluated in long double (64-bit
// significand on x86-64, or double elsewhere: then they carry the same bounds as the code, which
// the factors of 2 below already allow for).

// A value computed in double within a few u of its exact value v and stored as float (a square
// root of an exact integer, a difference of exact integers): float rounding adds 2^-24 |v|, the
// double evaluation a few 2^-53 |v|; 2^-23 |v| covers both with a factor ~2.
inline double float_of_exact(double v) { return std::ldexp(std::fabs(v), -23); }

// A sum of n values accumulated in double (any order) and stored as float, against the exact sum
// y: each double summation is within n u S of exact (S = sum of |terms|), the float rounding adds
// 2^-24 |y| <= 2^-24 S. Code and reference: 2^-24 S + 2 n 2^-53 S < 2^-23 S for n < 2^28.
inline double float_sum(double abs_sum) { return std::ldexp(abs_sum, -23); }

// A mean display position in mm: the code accumulates n integer pixel offsets |d| <= Q weighted in
// double (n u relative to sum w |d|, the weight sum likewise) and divides: (2n + 2) u Q pixels;
// mapping to mm (one division, two additions, one product) adds 2 u Q pixels + 3 u W mm, in all
// <= (2n + 7) u W mm (W the display extent along the axis). A deflection subtracts a float
// reference (u |d|). Stored as float: 2^-24 |value|. For n < 2^20 the double part is below
// 2^-31 W, so 2^-24 (|value| + W) bounds the difference from an exact reference, and 2^-23 leaves
// a factor 2.
inline double mean_position(double extent_mm, double value_abs) { return std::ldexp(extent_mm + value_abs, -23); }

// The weighted covariance of n contributing pixels with integer offsets |d| <= D from the first
// pixel (D <= the scatter diameter): the mean offset carries (2n + 2) u D, each centred offset
// (2n + 3) u D, its square or product twice that plus u D^2, the weighted sum n u W D^2 and the
// division by the (n u-accurate) weight sum: each entry within (6n + 9) u D^2 of exact. The 2 x 2
// perturbation has spectral norm <= twice its largest entry, and the eigenvalue formula
// (m +- hypot) adds ~4 u D^2: eigenvalues and the norm of the perturbation are within
// 16 (n + 3) u D^2 (the reference in long double: negligible).
inline double ellipse_covariance(long n, double D) { return 16.0 * (n + 3) * (kEps / 2) * D * D; }

// An ellipse axis 2 sqrt(lambda) stored as float, lambda within E of the exact lambda_ref:
// |sqrt a - sqrt b| <= min(sqrt |a - b|, |a - b| / sqrt b), so the axis is within
// min(2 sqrt E, 2 E / sqrt lambda_ref) plus the float rounding 2^-24 axis (2^-23 with the double
// square root's own u).
inline double ellipse_axis(double axis, double lambda_ref, double E) {
    const double root = 2.0 * std::sqrt(E);
    const double lin = lambda_ref > 0 ? 2.0 * E / std::sqrt(lambda_ref) : root;
    return (lin < root ? lin : root) + std::ldexp(std::fabs(axis), -23);
}

// The major-axis angle in degrees: by the Davis-Kahan sin-theta theorem a symmetric perturbation
// of norm E turns the leading eigenvector of a matrix with eigen gap g by at most
// asin(E / (g - E)) <= (pi / 2) E / (g - E) rad, i.e. 90 E / (g - E) degrees (any angle, 90, when
// g <= 2 E: the axis is then undetermined). atan2 and the scaling add a few u rad; the float
// rounding 2^-24 x 90 degrees: 2^-22 x 90 covers both.
inline double ellipse_angle_deg(double E, double gap) {
    const double turn = gap > 2.0 * E ? 90.0 * E / (gap - E) : 90.0;
    return (turn < 90.0 ? turn : 90.0) + std::ldexp(90.0, -22);
}

}  // namespace ltm::tol

namespace ltm::tol {

// ---- features_contrast: contrast-to-noise and robust outlier counts (features/Contrast.h) ----

// Statistical checks on a seeded synthetic image use a band of 3 standard errors: a correct
// implementation falls outside it with probability 0.27% (two-sided Gaussian) for a random seed;
// the seed is fixed, so the outcome is too.
constexpr double kStandardErrors = 3.0;

// Standard error of cnr = |mean_d - mean_s| / s from n_d defect and n_s surround pixels of Gaussian
// noise sigma with a true step c sigma (c = step / sigma), to first order (delta method):
//   the mean difference has variance sigma^2 (1 / n_d + 1 / n_s); divided by sigma it gives
//   cnr a variance 1 / n_d + 1 / n_s;
//   the sample variance s^2 has variance 2 sigma^4 / (n_s - 1), so s has standard error
//   sigma / sqrt(2 (n_s - 1)) (ds = d(s^2) / (2 sigma)), relative 1 / sqrt(2 (n_s - 1)), which
//   moves cnr by c / sqrt(2 (n_s - 1));
//   the terms are independent (a Gaussian sample's mean and variance are independent, and the
//   defect's pixels are disjoint from the surround's), so their variances add:
//   SE = sqrt(1 / n_d + 1 / n_s + c^2 / (2 (n_s - 1))).
// Storing the samples as float32 changes each by 2^-24 relative, ~1e-8 of the step: negligible.
inline double cnr_standard_error(double c, long n_defect, long n_surround) {
    return std::sqrt(1.0 / static_cast<double>(n_defect) + 1.0 / static_cast<double>(n_surround) +
                     c * c / (2.0 * static_cast<double>(n_surround - 1)));
}

// CNR of a few small integers and halves against the formula evaluated by hand in double: sums,
// means and deviations of such values are exact; what rounds is the variance quotient, the
// square root and the final quotient, u = eps / 2 each, in both the code and the reference:
// < 6 u = 3 eps relative; 8 eps leaves a margin.
inline double contrast_exact() { return 8.0 * kEps; }

// kMadToSigma = 1.4826 is 1 / Phi^-1(3/4) = 1.4826022... rounded to 4 decimals: off by at most
// half a unit in the 4th decimal, 5e-5 (the quantile itself is found to ~1e-12).
inline double mad_constant_rounding() { return 5e-5; }

// A planted-outlier test must not see a pure-noise false alarm: the probability that any of n
// Gaussian noise pixels exceeds k sigma is at most n P(|Z| > k) (union bound); the test's image
// is chosen so this is below 1e-3.
constexpr double kNegligibleProbability = 1e-3;

}  // namespace ltm::tol

namespace ltm::tol {

// ---- trace_polynomial, trace_grin: roots and closed-form curved paths ----

// A simple root x* of p(x) = sum c_i x^i (degree n) located by sign changes and polished until
// the bracket cannot shrink: the computed root is where Horner's evaluation of p changes sign,
// which the rounding of the evaluation moves by at most (2 n u sum_i |c_i| |x*|^i) / |p'(x*)|
// (Higham, Accuracy and Stability, 2nd ed., Sec. 5.1: Horner's error bound gamma_2n times the
// absolute sum, over the slope); twice that covers the last bisection step.
inline double poly_root(int degree, double abs_sum, double slope) {
    return 2.0 * (2.0 * degree * (kEps / 2) * abs_sum) / std::fabs(slope);
}

// A closed-form graded-index path (trace/GrinPath.h) against its closed form evaluated in the
// test, per interface: the crossing's parameter is polished until f = F(r(tau)) changes sign,
// which rounding (|F| evaluated to ~8 u L^2 for a quadric of size L) moves by 8 u L^2 / |f'| with
// |f'| = 2 |L (r - c)| |p| cos(theta) ~ 2 L n cos(theta): a position error n dtau <= 4 u L / cos;
// the test rays meet their surfaces at cos >= 1/8, so <= 32 u L; evaluating r(tau) (sines,
// cosines and ~16 rounded products and sums of magnitude <= L) and the rotation into and out of
// H's eigenbasis (~12 more) add ~30 u L: ~64 u L per interface and implementation, twice for the
// tracer and the test's own closed form, times (1 + kappa) for the path's sensitivity, over the
// n interfaces plus the final propagation: 128 (n + 1) u L (1 + kappa).
inline double grin_closed_form(int interfaces, double scale, double kappa) {
    return 128.0 * (interfaces + 1) * (kEps / 2) * scale * (1.0 + kappa);
}

}  // namespace ltm::tol

namespace ltm::tol {

// ---- geometry_index_field: index fields and the exact range of a quadratic over the lens solid ----
// u = eps / 2 below. Q = |c| + |b| L + |H|_F L^2 is the magnitude of q(x) = c + b . x + x^T H x / 2
// at |x| <= L: |b . x| <= |b| L and sum_ij |x_i H_ij x_j| <= |H|_F |x|^2 (Cauchy-Schwarz; the
// factor 1/2 is dropped for margin).

// q evaluated in double: H x (3 products and 2 sums per component), the two dot products, the
// halving (exact) and the two final sums put every term through at most 8 roundings, so the result
// is within gamma_8 ~ 8 u Q of exact. Two evaluations of one field by different formulas (the
// quadratic form and a hand formula, itself of <= 8 roundings): 16 u Q = 8 eps Q; 16 eps Q leaves
// a factor 2.
inline double quadratic_agreement(double magnitude) { return 16.0 * kEps * magnitude; }

// An extreme reported by quadratic_range against q at a point of the solid, or against a closed
// form, where L bounds every coordinate and also every sphere centre and radius the points are
// computed from (x = C + R u):
//   - each of the two values carries the evaluation error 8 u Q (above): 16 u Q;
//   - each point is off its exact position by the rounding of its coordinates, <= 8 u L (C + R u
//     with u normalised; a sample accepted by Lens::contains within the rounding of z_front and
//     z_back). Along its stratum an exact extreme is stationary, so only the component across it
//     changes q, by <= |grad q| 8 u L <= 8 u (|b| L + |H|_F L^2): 16 u (|b| L + |H|_F L^2) for two;
//   - the eigendecomposition and the secular-equation roots are backward stable: the candidates
//     are exact stationary points of the stratum's form perturbed by ~8 u relative in
//     A = R^2 H / 2 and beta = R (b + H C), which moves the extreme by <= 8 u (|H|_F L^2 + |b| L).
// In all <= 16 u |c| + 40 u |b| L + 40 u |H|_F L^2 <= 40 u Q; 80 u Q = 40 eps Q leaves a factor 2.
inline double quadratic_extreme(double magnitude) { return 40.0 * kEps * magnitude; }

// The Luneburg ball (R = 10, ior = sqrt 2 rounded, g = 0.0707106781186548 typed to 15 significant
// digits) at its surface: n^2 = ior^2 (1 - g^2 R^2) is exactly 1 for the exact constants. The
// typed g is within half a unit of its last digit, 5e-17, of 1 / (R sqrt 2), which moves n^2 by
// |d n^2 / dg| 5e-17 = 2 ior^2 g R^2 5e-17 = 28.3 x 5e-17 = 1.5e-15; ior^2 is 2 (1 + 2 u) at most,
// 4.4e-16; the extreme itself is within quadratic_extreme's 40 u Q with Q = 2 + |H|_F R^2 =
// 2 + sqrt 3 x 0.02 x 100 = 5.5: 2.5e-14. So |n^2 - 1| < 2.7e-14 and |n - 1| = |n^2 - 1| / (n + 1)
// < 1.4e-14; 3e-14 leaves a factor 2.
inline double luneburg_surface_index() { return 3e-14; }

}  // namespace ltm::tol

namespace ltm::tol {

// ---- validation_grin: the GRIN reference solver (validation/GrinReference.h) against closed forms ----

// A path of the GRIN reference against an exact closed-form path. The integrator accepts a step
// when its local error estimate is below tol x size in every position component and below
// tol x p_scale in every momentum component (GrinReference.cpp, "Step-size control"); the kept
// result (the extrapolated T_{8,8}) is at least as accurate as the estimated T_{8,7} (local
// extrapolation, in the asymptotic regime of the step sizes). A local error then propagates like
// a perturbation of the ray at that point (Lady Windermere's fan, Hairer, Norsett, Wanner, Solving
// ODEs I, Sec. II.3), bounded with the assumption of validation/ValidationTolerance.h (a sub-path
// magnifies no more than the whole path, kappa): a position error e moves the later vertices and
// the display hit by <= (1 + kappa) e; a momentum error tol p_scale turns the direction by
// <= tol p_scale / n_min, which moves them by <= (1 + kappa) L tol p_scale / n_min. Over `steps`
// steps (accepted steps and the event-locating re-steps, +1 for the final partial step of each
// leg, counted once in all):
//   (1 + kappa) (steps + 1) tol (size + L p_ratio),   p_ratio = p_scale / n_min.
// Rounding: the reference's own, C_ref u L (1 + kappa) with C_ref = grin_reference_constant of
// validation/ValidationTolerance.h (its interfaces, roots, state updates and increments, derived
// there), and the closed form's, evaluated in double within the "+ 2" of closed_form_path:
// 128 u L (1 + kappa).
inline double grin_reference_path(int steps, double reference_constant, double tol, double size, double L,
                                  double p_ratio, double kappa) {
    return (1.0 + kappa) * ((steps + 1) * tol * (size + L * p_ratio) + (reference_constant + 128.0) * (kEps / 2) * L);
}

// The same for a direction (rad), with L = 1 in the rounding terms:
//   (1 + kappa_dir) [(steps + 1) tol (size / L + p_ratio) + (C_ref + 128) u].
inline double grin_reference_direction(int steps, double reference_constant, double tol, double size, double L,
                                       double p_ratio, double kappa_dir) {
    return (1.0 + kappa_dir) *
           ((steps + 1) * tol * (size / L + p_ratio) + (reference_constant + 128.0) * (kEps / 2));
}

// The deflection of a ray by a weak smooth spherical inclusion n = n0 + dn (1 - r^2/a^2)^2 (r < a)
// against its first-order value theta1(b) = -(dn / n0) 16 b (a^2 - b^2)^(3/2) / (3 a^4) (derived
// in validation_grin.cpp, SmoothInclusion). The exact ray has d/ds (n dx/ds) = dn/dx, so its final
// transverse momentum is P = int dn/dx (x(z), z) (ds/dz) dz along the TRUE path, and sin(theta)
// = P / n0; the first order theta1 is P / n0 with the integrand on the straight line x = b and
// ds = dz. With eps = |dn| / n_min and the profile's bounds (q = (1 - r^2/a^2)^2:
// |dq/dx| = |4 x (1 - r^2/a^2)| / a^2 <= 8 / (3 sqrt(3) a) ~ 1.54 / a, at r = a / sqrt 3;
// |d^2q/dx^2| = |-4 (1 - r^2/a^2) + 8 x^2 / a^2| / a^2 <= 8 / a^2):
//   the direction turns by at most |theta(z)| <= 1.54 eps (z + a) / a since the ray entered the
//   inclusion (at z >= -a), so it leaves x = b by at most int_{-a}^{z} |theta| <= 0.77 eps (z + a)^2 / a
//   <= 3.08 eps a (both integrands vanish outside |z| < a);
//   (i) sampling the gradient off the line: <= 8 dn / a^2 x 3.08 eps a x 2a = 49.3 dn eps;
//   (ii) ds / dz - 1 = 1 / cos(theta) - 1 <= theta^2 / 2: <= 1.54 dn / a x (3.08 eps)^2 / 2 x 2a = 14.6 dn eps^2.
// Divided by n0 (|dn| / n0 <= eps): |sin(theta) - theta1| <= 49.3 eps^2 + 14.6 eps^3 (and higher
// orders in eps^4), below 64 eps^2 for every eps <= 0.5 (the inclusions here have eps <= 0.014).
inline double weak_lens_second_order(double eps) { return 64.0 * eps * eps; }

}  // namespace ltm::tol

namespace ltm::tol {

// An identity on the outputs of a closed form of validation/GrinClosedForms.h evaluated in double
// (|p|^2 = n^2 along a path, a path function against the exit value, two closed forms of the same
// path): each side is <= 32 roundings (a trigonometric or hyperbolic function within 1 ulp counted
// as 2, the argument's rounding as 1 more), each relative to operands of magnitude <= M (the
// identity's terms, e.g. R for positions in a sphere of radius R, n^2 for |p|^2, n0 / |k| where a
// form divides by the gradient k): both sides within 32 u M, their difference within 64 u M.
inline double closed_form_identity(double magnitude) { return 64.0 * (kEps / 2) * magnitude; }

}  // namespace ltm::tol

namespace ltm::tol {

// ---- geometry_tetmesh: tetrahedral meshes (geometry/TetMesh.h) ----

// Total volume of a tetrahedral mesh against the volume its input boundary encloses, both summed
// in long double from the double coordinates (unit roundoff u_L = epsilon of long double).
//   With exact arithmetic the tetrahedra's volumes add up to the volume enclosed by the mesh's
//   own boundary faces (inner faces cancel). That surface is the input surface except where
//   Steiner points were put on it: TetGen computes them from a few input vertices (segment
//   midpoints, circumcentres of boundary triangles: a few dozen rounded operations on
//   coordinates <= L), the bisection post-pass as edge midpoints; each lands within 64 eps L of
//   the input triangle it belongs to. Moving a surface's vertices by <= d sweeps a volume
//   <= d x area, so the two volumes differ by <= 64 eps L A.
//   Each determinant in long double is within ~10 u_L of the product of its edge lengths
//   |u||v||w| (the terms of abs_sum are those products / 6), and summing n terms adds n u_L of
//   their absolute sum: (n + 16) u_L abs_sum bounds both evaluations' rounding when abs_sum
//   covers both sums' terms.
inline double tetmesh_volume(double L, double area, long double abs_sum, size_t terms) {
    return 64.0 * kEps * L * area +
           static_cast<double>((static_cast<long double>(terms) + 16) * std::numeric_limits<long double>::epsilon() *
                               abs_sum);
}

// Linear interpolation of n^2 checked at a point x = sum l_i p_i of a tetrahedron, against the
// field evaluated at x, both in double: the field's own evaluation (about ten operations on
// values <= n2_max) is within 16 eps n2_max of its exact value at the computed x; the computed x
// is within 4 eps L of the exact combination (three products and additions per coordinate),
// which moves the field by <= |grad n^2| 4 eps L; the interpolated value sum l_i n2_i by
// <= 8 eps n2_max. In all 24 eps n2_max + 4 eps L |grad n^2|_max; doubled for margin.
inline double interpolation_rounding(double n2_max, double L, double grad_max) {
    return 48.0 * kEps * n2_max + 8.0 * kEps * L * grad_max;
}

// Smallest enclosing ball of four points, by the library (the best of 11 candidate centres) and
// by the test's own Welzl recursion (circumcentres solved as linear systems): both compute the
// circumcentre of the same support set, each from a linear system whose condition number kappa is
// below ~1e3 for the tetrahedra TetGen makes (dihedral angles above ~5 degrees; measured >= 6);
// the centre is then within ~8 kappa eps r of the exact one and the radius (1-Lipschitz in the
// centre) as well: < 2e-12 r. 1e-9 r allows kappa up to 5e5.
constexpr double kEnclosingRadiusRelative = 1e-9;

// Halving the tolerance on n^2 with a constant Hessian bound M shrinks the largest allowed
// enclosing radius sqrt(2 t / M) by sqrt 2, so the count of tetrahedra filling a fixed volume
// grows by 2^(3/2) = 2.83 in the limit. Before the limit the layer along the boundary (whose
// count grows like area / r^2: a factor 2) and the discreteness of Delaunay refinement (sizes
// fall between about r_max / 2 and r_max, and the mix shifts between tolerances) move it: the
// ratio is asserted in [2, 4.5], i.e. at least the surface's scaling and at most 1.6 times the
// volume's.
constexpr double kHalvingCountRatioLow = 2.0;
constexpr double kHalvingCountRatioHigh = 4.5;

// n = sqrt(n2) as written to a VTU file, squared again by the reader, against n2 <= v: the root
// is correctly rounded (n (1 + d), |d| <= u = eps / 2) and so is the square, so the result is
// n2 (1 + d)^2 (1 + d') within 3 u n2 of n2 (to first order); 2 eps v covers it.
inline double square_of_root(double v) { return 2.0 * kEps * v; }

}  // namespace ltm::tol

namespace ltm::tol {

// ---- validation_torus: the tracer's torus roots (trace/Intersect.cpp) against the exact reference ----
// (validation/TorusReference.h: exact roots rounded to double). u = eps / 2 below.
//
// The tracer solves f(s) = sum_i c_i s^i = 0 along x = p + s d, t = tm + s, where (d unit)
// tm = (C - o).d and p = o + tm d - C are computed in double, and
//   c0 = A^2 - 4 R^2 (|p|^2 - (p.a)^2), c1 = 8 R^2 (p.a)(d.a), c2 = 2 A - 4 R^2 (1 - (d.a)^2), c3 = 0,
//   c4 = 1, A = |p|^2 + R^2 - r^2,
// the textbook quartic f(x) = (|x|^2 + R^2 - r^2)^2 - 4 R^2 (|x|^2 - (x.a)^2) (the reference's f).
// With Abar = |p|^2 + R^2 + r^2, X = |p|^2 + s^2 (= |x|^2 up to rounding), L = |o| + |tm| + |C| and
//   M(s) = Abar^2 + 4 R^2 (|p|^2 + (p.a)^2) + 8 R^2 |p.a| |d.a| |s| + (2 Abar + 4 R^2 (1 + (d.a)^2)) s^2 + s^4
// (the absolute values of every term of every coefficient, times |s|^i), the value the tracer
// computes at s differs from the exact f at t = tm + s by at most
//   E(s) = u [64 M(s) + 96 R r (R + r) L + 28 |2 (X - R^2 - r^2)| |s| L]:
//  (1) coefficients and evaluation: c0 is ~12 roundings deep (|p|^2 and p.a 5 each, A 2 more, the
//      squares, products and the difference 3), each relative to the magnitude of its terms (c0
//      cancels: |c0| << Abar^2 near the tube, so its error is relative to m0, not to c0); c2 ~10,
//      c1 and c4 fewer: <= 30 u m_i each. Horner's rule adds gamma_8 ~ 8 u sum |c_i| |s|^i <=
//      8 u M(s) (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., Sec. 5.1). In all
//      38 u M(s) <= 64 u M(s);
//  (2) the line: p = o + tm d - C is rounded 3 times per component, each relative to <= L, so
//      |dp| <= 3 sqrt(3) u L <= 6 u L. Moving the line by dp changes f by <= |grad f| |dp|. As
//      f = ((rho - R)^2 + h^2 - r^2) ((rho + R)^2 + h^2 - r^2) (rho, h: distance from the axis and
//      height) and the second factor is 4 R rho on the tube, grad f = 8 R r rho n there, |grad f|
//      <= 8 R r (R + r); doubled for the points off the tube by the tolerances below (<< r):
//      16 R r (R + r) 6 u L = 96 u R r (R + r) L;
//  (3) the tracer takes p.d = 0 and so drops the odd terms 2 s (p.d) of |x|^2. The rounding of tm
//      (the difference C - o, the dot product: <= 8 u (|C| + |o|)) and the component of dp along d
//      (<= 6 u L) leave |p.d| <= 14 u L; with df / d|x|^2 = 2 (|x|^2 - R^2 - r^2) this changes f by
//      <= 2 |s| 14 u L |2 (X - R^2 - r^2)|.
inline double torus_f_error(double R, double r, double pp, double pa, double da, double s, double L) {
    const double u = kEps / 2, R2 = R * R, abar = pp + R2 + r * r, X = pp + s * s, as = std::fabs(s);
    const double M = abar * abar + 4 * R2 * (pp + pa * pa) + 8 * R2 * std::fabs(pa * da) * as +
                     (2 * abar + 4 * R2 * (1 + da * da)) * s * s + s * s * s * s;
    return u * (64 * M + 96 * R * r * (R + r) * L + 28 * std::fabs(2 * (X - R2 - r * r)) * as * L);
}

// A simple root t* of f with slope f' and curvature K = f'' there, the computed f within E of the
// exact one. In the quadratic model f(t* + e) = f' e + K e^2 / 2 the perturbed root solves
// f' e + K e^2 / 2 = -df (|df| <= E): e = -2 df / (f' + sqrt(f'^2 - 2 K df)), so
// |e| <= 2 E / |f'| (the square root is real and >= 0 while the root exists), and, from
// |sqrt a - sqrt b| <= sqrt |a - b| on e = (sqrt(f'^2 - 2 K df) - f') / K, |e| <= sqrt(2 E / |K|),
// which is the smaller one near tangency (f'^2 < 2 K E): there the root error grows like sqrt(E),
// i.e. like sqrt(eps). (The model neglects the cubic term, a relative |f'''| e / (3 |K|) ~ e / (3 r)
// for f''' ~ K / r; the tests do not rely on it to decide whether a root must be found: they check
// with the exact reference that f changes sign across t* +- e with |f| > E at both ends and that f'
// has no root in between, and only then require the traced root in the window.) To this the tracer's stopping rule adds 2 ulps of s (a step below
// 2 eps |s|, Polynomial.h: <= 8 u |s|), t = tm + s one rounding u |t| and the reference's own
// rounding to double u |t|.
inline double torus_root(double E, double slope, double curvature, double t, double s) {
    const double u = kEps / 2;
    const double simple = slope != 0 ? 2 * E / std::fabs(slope) : INFINITY;
    const double tangent = curvature != 0 ? std::sqrt(2 * E / std::fabs(curvature)) : INFINITY;
    return std::fmin(simple, tangent) + 8 * u * std::fabs(s) + 2 * u * std::fabs(t);
}

// Near a root of multiplicity m (a tangency: m = 2, or higher contact) f(t* + e) = f^(m) e^m / m!
// to leading order, and a perturbation |df| <= E can only create roots where |f| <= E: within
// (m! E / |f^(m)|)^(1/m) of t*. For a near-tangent pair of simple roots t1 < t2 (the model
// f = f_c + K (t - t_c)^2 / 2 about their midpoint t_c, t_{1,2} = t_c -+ sqrt(-2 f_c / K)) the
// perturbed roots t_c +- sqrt(2 (-f_c - df) / K) lie within sqrt(2 E / K) of [t1, t2]
// (sqrt(a + b) <= sqrt a + sqrt b). Plus the roundings of torus_root (8 u |s| + 2 u |t|). Any traced
// root in the band is checked by its residual, |f(t)| <= E + |f'(t)| (8 u |s| + 2 u |t|) (a
// perturbation of f by E can create a root only where the exact |f| is at most E, up to the
// stopping slack), and one near an exact tangency also by this window.
inline double torus_contact_window(double E, int multiplicity, double derivative_m, double t, double s) {
    const double u = kEps / 2;
    double factorial = 1;
    for (int k = 2; k <= multiplicity; ++k) factorial *= k;
    return std::pow(factorial * E / std::fabs(derivative_m), 1.0 / multiplicity) + 8 * u * std::fabs(s) +
           2 * u * std::fabs(t);
}
// ==== trace_render: defect walls refined from the mesh against closed forms =======================
// (This section and the "moved literals" sections below belong to the tests' tolerance move; the
// torus tolerances are kept elsewhere, so the two can be merged section by section.)

// A principal path of the refined tracer against the closed-form tracer of the test (planes,
// cylinders and balls intersected in double, Snell's law in vector form): two independent
// computations of the same exact path, each with validation/ValidationTolerance.h's bound
// 64 (n + 1) u L (1 + kappa) (<= 64 roundings per interface, n interfaces plus the propagation to
// the display, kappa the path's sensitivity, L its length scale); the test's closed form is that
// count's own operations (the ball as AnalyticScene's sphere, a plane or a half-space clip ~6,
// the cylinder ~25) and the tracer's refinement solves the same roots of its tagged surfaces
// (trace/Intersect.cpp: the same counts), its spawn step moving the origin along the new ray (no
// sideways error beyond one rounding of |o| <= L). Their difference: 2 x 64 (n + 1) u L (1 + kappa).
// A mesh hit left unrefined is off by the facet's float rounding (~1e-7 relative) or its chord
// error (up to ~5e-4 mm here): 1e4 times more than this for the scenes tested.
inline double refined_path_position(int interfaces, double L, double kappa) {
    return 2.0 * 64.0 * (interfaces + 1) * (kEps / 2) * L * (1.0 + kappa);
}
// The same for the final direction (rad): L = 1 and kappa_dir.
inline double refined_path_direction(int interfaces, double kappa_dir) {
    return 2.0 * 64.0 * (interfaces + 1) * (kEps / 2) * (1.0 + kappa_dir);
}
// A unit direction computed from two vertices each within e of exact, a distance l apart: the
// difference vector is within 2 e, and normalising a vector of length l turns it by at most
// 2 e / l (plus a few u, far below e / l for e >= 64 u L and l <= L).
inline double direction_from_vertices(double vertex_error, double l) { return 2.0 * vertex_error / l; }

}  // namespace ltm::tol

namespace ltm::tol {

// A groove's torus as the scene builds it (defects/DefectSolid.cpp make_scratch, U profile, and
// defects/ScratchPath.cpp circle_surface) against the torus of the scene's nominal numbers: the
// tube radius rb = (w^2 / 4 + d^2) / (2 d) is 4 roundings from exact, the centre o + u (h0 + s sh
// + t th) with t = d - rb and the major radius q0 + s sq + t tq a few more each (<= 8 per number),
// each relative to at most M = |C| + R + r. So every number is within 8 u M of its nominal value
// and the surface within 3 x 8 u M = 24 u M of the nominal one; a crossing moves along the unit ray
// by that over |cos| of the incidence, cos = f'(t) / |grad f| = f'(t) / (8 R r rho) on the tube
// (see torus_f_error).
inline double torus_built_shift(double magnitude, double cos_incidence) {
    return 24.0 * (kEps / 2) * magnitude / std::fabs(cos_incidence);
}

// ==== moved literals: geometry, intersections, sampling (were bare numbers in the tests) ==========
// u = eps / 2 below. "k roundings relative to M": a result reached through a chain of k correctly
// rounded operations on operands of magnitude <= M is within gamma_k M ~ k u M of exact (Higham,
// Accuracy and Stability, 2nd ed., Lemma 3.1); libm's sin, cos, asin, atan2 are within 1 ulp,
// counted as 2 roundings.

// defects_sampling: a face point (rho cos phi, rho sin phi, z(rho)) against z evaluated at
// rho' = hypot(x, y): cos, sin (2 roundings each), the two products and hypot put rho' within
// 8 u rho of rho, which moves z by slope x 8 u a (slope = |dz / drho| <= a / sqrt(R^2 - a^2) on a
// spherical cap); the two evaluations of z (the same function, ~8 roundings of |z| <= z_max each)
// add 16 u z_max. Doubled: 16 u (a slope + 2 z_max). (Was 1e-12: tightened.)
inline double face_point_height(double a, double slope, double z_max) {
    return 16.0 * (kEps / 2) * (a * slope + 2.0 * z_max);
}

// defects_sampling: Euler angles (degrees) -> rotation -> Euler angles. The input angles become
// radians with 2 roundings (<= 2 pi u absolute each), which moves R's entries by <= 6 pi u < 19 u;
// each entry (<= 2 products of 3 sines and cosines, a sum) adds <= 8 u: <= 27 u < 32 u. Recovering
// beta = asin(-R20) divides an entry error by cos(beta); alpha, gamma = atan2 of two entries of
// magnitude cos(beta): an angle error <= 32 u / cos(beta), plus atan2's own 2 u |angle| <= 2 pi u;
// back to degrees x 180 / pi and 2 more roundings of |e| <= 180. Doubled:
//   ((64 / cos(beta) + 4 pi) u) 180 / pi + 720 u.
// For |beta| <= 89 degrees (cos >= 0.01745) this is <= 2.4e-11 degrees. (Was 1e-9: tightened.)
inline double euler_roundtrip_deg(double cos_beta) {
    return (64.0 / cos_beta + 4.0 * 3.141592653589793) * (kEps / 2) * (180.0 / 3.141592653589793) +
           720.0 * (kEps / 2);
}
// ... and at gimbal lock (beta = +-90), the rotation rebuilt from the recovered angles against the
// original, entry by entry: R's entries within 27 u (above), the recovered combination angle from
// atan2 of two entries of magnitude 1 within 27 u + 2 pi u, its trip through degrees 4 pi u, the
// rebuilt entries' own 8 u plus that angle error, and the cos(fl(pi/2)) = 6e-17 left of the exact
// gimbal identity (< u): < 27 + 8 + 33 + 13 + 1 < 82 u; 128 u = 64 eps. (Was 1e-12: tightened.)
inline double gimbal_roundtrip_entry() { return 64.0 * kEps; }

// geometry_export: the signed volume of a closed mesh, sum over faces of det(p0, p1, p2) / 6, for
// a small mesh against a reference sum: each determinant within 8 u of the product of its edge
// lengths, each of the `terms` additions within u of the absolute sum S of the terms (both sums'
// terms counted in S), the division 1 more: (terms + 16) u S.
// (Was 1e-12; the integer vertices here make most operations exact: tightened.)
inline double mesh_signed_volume(int terms, double abs_sum) { return (terms + 16) * (kEps / 2) * abs_sum; }

// geometry_lens: Lens::volume = pi a^2 t + sag_volume(r2) - sag_volume(r1), each term <= 12
// roundings relative to itself, two sums, against a closed form of <= 8 roundings: 32 u S, S the
// sum of the terms' magnitudes. (Was 1e-12 V: tightened.)
inline double lens_volume(double abs_terms) { return 32.0 * (kEps / 2) * abs_terms; }
// ... against 64-point Gauss-Legendre quadrature of (z_back - z_front) 2 pi rho: truncation is
// negligible (the integrand's nearest singularity is the branch point rho = |R| >= 30 for the
// lenses tested, a = 12.5: Bernstein parameter rho_B = 3.8 + sqrt(3.8^2 - 1) = 7.5 for [0, 1],
// error ~ rho_B^-128 < 1e-100); rounding: the nodes are Newton-converged to |dz| < 1e-16 (a few u),
// the weights 1 / ((1 - z^2) P_n'^2) carry the stable three-term recurrence's ~2 n u = 128 u
// squared: 256 u; the 64-term sum 64 u; each integrand's difference z_back - z_front 8 u (|z_b| +
// |z_f|) / (z_b - z_f) <= 40 u (the ratio is <= 5 here); the closed form 32 u: < 400 u; 512 u
// relative. (Was 1e-12 relative: tightened.)
inline double quadrature_volume_relative() { return 512.0 * (kEps / 2); }
// ... a cap's area 2 pi |R| sag against 2 pi a^2: ~6 roundings each side: 16 u A. (Was 1e-12.)
inline double cap_area(double A) { return 16.0 * (kEps / 2) * A; }
// ... distances of points with small integer coordinates to the faces and rim of the lens
// (50, -50, 6, 25): the nearest points are found through a distance to the sphere's centre
// |p - c| - |R| = 47 - 50 and |rho - a| = 12.5, exact in double (integers and halves, a square
// root of a perfect square is correctly rounded to it): error 0 up to the final rounding of the
// result, <= u |v|. 2 eps |v| leaves a factor 4. (Was 1e-14: tightened.)
inline double exact_operands(double v) { return 2.0 * kEps * std::fabs(v); }
// ... the distance from a point to a cap's edge circle, hypot(rho - a, z - z_edge), with
// z = z_edge - 4 computed: z - z_edge carries 2 roundings of magnitude M = |z_edge| + 4, hypot and
// rho - a 2 more of the result: 16 u M covers them with a factor 2. (Was 1e-12: tightened.)
inline double cap_edge_distance(double M) { return 16.0 * (kEps / 2) * M; }

// geometry_surface: distances, projections and normals at points with small integer coordinates
// and results of magnitude <= 4: each side (the code and the test's closed form, e.g. 1 + 2 x 0.6
// for a projection onto a sphere of radius 2 along (3, 4, 0) / 5) is <= 4 correctly rounded
// operations on exact operands or correctly rounded constants (0.6, 0.8, sqrt 2, tan(pi / 4)).
// The values before each side's last rounding differ from the exact result by <= 3 u |q|, so the
// two rounded results differ by at most 2 ulps of |q| <= 4 when |q| < 2, one of |q| in [2, 4)
// (ulp = 4.4e-16 there): <= 8.9e-16 in every case, below the literal 1e-15, which is kept (a
// plain count k u M with margin would allow ~2e-15: the literal is tighter than that count and
// holds by this ulp argument).
constexpr double kSurfaceExampleAbs = 1e-15;
// ... a cone's distance to its own projection of a point (|x| <= 5.5): a plain count (the
// projection's ~12 roundings and the distance's ~8, 20 u x 5.5 = 1.2e-14) exceeds the literal
// 1e-14, which is kept: the projection lands on the generator line of the point's own meridian
// coordinates (q, h), which the distance evaluation recomputes from the projected point, so the
// rounding of the meridian frame cancels to first order and only the two evaluations' final
// ~8 roundings each remain: <= 16 u 5.5 = 9.8e-15.
constexpr double kConeProjectionAbs = 1e-14;
// ... the closest / farthest point of an ellipsoid (semi-axes >= 0.4) from the bisection for the
// Lagrange multiplier t, to full precision: f(x) - 1 = F(t) evaluated, <= |F'(t)| ulp(t) (the last
// bracket) + ~16 u; F' = -2 sum e_i^2 y_i^2 / (t + e_i^2)^3 is <= ~1e3 for the test's points
// (|y| <= 6 sqrt 3, t + e_i^2 >= ~0.1 away from the pole for points off the axes; the on-axis and
// inside trials were the literal's origin): ~1e-12. Kept.
constexpr double kEllipsoidExtremeOnSurface = 1e-12;
// ... an ellipsoid with equal semi-axes 2 at centre (1, 1, 1), rotated: the distance goes through
// the frame (9 products, 6 sums, with cos/sin of the rotation: 20 roundings of magnitude <= 4)
// and the scaled radius: 32 u x 4 = 1.4e-14. (Was 1e-12: tightened.)
inline double rotated_ellipsoid_distance() { return 32.0 * (kEps / 2) * 4.0; }

// study_ground_truth: areas of a unit disk within boxes. The whole disk, the half and the
// quarter are exact: at the breakpoints x = +-1, 0 the primitive is (x sqrt(1 - x^2) + asin x) / 2
// with sqrt(0) = 0 and asin(+-1) = +-fl(pi / 2) (correctly rounded), so every piece is fl(pi / 2)
// times a power of 2, equal to fl(pi), fl(pi / 2), fl(pi / 4) as M_PI's expressions are; the box
// inside the disk is y (b - a) on halves: 1 exactly. The segment x > 1/2 (acos 0.5 - 0.5 sqrt 0.75
// = 0.614) goes through asin(0.5) (correctly rounded to fl(pi / 6) in glibc), sqrt(0.75), 0.5 x
// and two differences of values < 1.6 rounded to results < 1: <= 5 roundings of ulp <= 2.2e-16,
// i.e. <= 5.6e-16 for each side, < 1e-15 for the two. The literal is kept (a plain 8 u M count
// with M = pi would allow 2.8e-15: the literal is tighter and holds by this).
constexpr double kDiskAreaAbs = 1e-15;
// ... the summed footprint fractions of a defect against (1 - R0) pi r^2 / A_pixel: a Monte Carlo
// estimate whose standard error is below sqrt(perimeter pixels / samples) ~ 0.2 pixels (only
// pixels on the disk's edge are fractional): 1 pixel is > 5 standard errors. Kept.
constexpr double kFootprintPixels = 1.0;

// trace_grin: the arc length of a parabolic graded-index path: GrinPath.h's Gauss-Legendre is
// refined to 1e-12 relative (its own stated accuracy); the closed form's rounding is ~1e-14
// relative. Kept: that is the code's contract.
constexpr double kGrinArcLengthRelative = 1e-12;

// trace_optics: intersection roots against exact values.
// A plane: t = dot(origin - o, axis) / dot(d, axis), d = (0, 3, 4) / 5 normalised (0.6, 0.8 within
// u), the dot of integers exact, the quotient u: within 4 u |t|; 8 u |t| with margin.
// (Was 1e-14: tightened.)
inline double plane_root(double t) { return 8.0 * (kEps / 2) * std::fabs(t); }
// A root of a t^2 + b t + c = 0 whose coefficients are each within 10 u of their magnitudes
// (a <= 1, |b| <= 2 M, |c| <= M^2, with M = |o - apex| or |o - centre| + radius; the cone's
// cos^2(angle) adds 2 u relative): the coefficient errors move the root by (|da| t^2 + |db| t +
// |dc|) / |p'(t)| <= 10 u (t + M)^2 / sqrt(D) (|p'| = sqrt(D) at a root, D the discriminant);
// solving (the discriminant's rounding relative to b^2 + 4 |a c| <= 8 (t + M)^2, halved by the
// square root) as much again: 32 u (t + M)^2 / sqrt(D) with margin. (Was 1e-12: tightened.)
inline double quadratic_root(double t, double M, double sqrt_disc) {
    return 32.0 * (kEps / 2) * (t + M) * (t + M) / sqrt_disc;
}

// trace_render, validation_render: the entries of T are float32 of (count / n): n x float(c / n) is
// within n 2^-24 (c / n) <= 2^-24 n... relative to c <= n: |n T - c| <= 2^-24 c <= 2^-24 n.
// (Was 1e-5 for n = 36: tightened to 2.1e-6.)
inline double float_count(int n) { return std::ldexp(static_cast<double>(n), -24); }

}  // namespace ltm::tol

namespace ltm::tol {

// ---- acquire_*: simulated acquisition (acquire/) ----

// acquire_sensor's Z-tests of the noise model's mean and variance use bonferroni_z(n) with n the
// number of statistics tested in the file (family-wise false alarm kFamilyAlpha, seeded, so the
// outcome is fixed). The variance statistic's standard error is sqrt((mu4 - sigma^4 (n - 3) /
// (n - 1)) / n) for n samples (the variance of the sample variance, any distribution; Cramer,
// Mathematical Methods of Statistics, 1946, Sec. 27.4), mu4 the closed-form central fourth moment.

// A decoded display position in mm, d = -W/2 + (c + 1/2) W / Q for an exact integer or a double
// column c: three rounded operations on magnitudes <= W (3 u W) and the float rounding of the
// result (2^-24 |d|): 2^-23 (W + |d|) covers both with a factor 2 (u = 2^-53).
inline double decoded_position(double extent_mm, double value_abs) { return std::ldexp(extent_mm + value_abs, -23); }

// Phase shifting with the display quantised to `bits` and gamma g >= 1: each pattern's radiance
// is off the ideal sinusoid by at most the half step 2^-bits / 2 of the command, times the
// largest slope g of v^g on [0, 1], i.e. |dL| <= g 2^-(bits+1), so |dy_j| <= (1 - b) t g 2^-(bits+1)
// for a row holding t. The phase sum's modulus is (1 - b) t s / 4 for s steps (Patterns.h), so
// the phase moves by at most sum_j |dy_j| / modulus <= 4 g 2^-(bits+1) = g 2^-(bits-1) rad (the
// float storage of the commands, 2^-24, and the double sums, ~s u, far below), and the column by
// period / (2 pi) times that; in mm, times W / Q. Plus decoded_position's rounding.
inline double phase_position(double period, double gamma, int bits, double pixel_mm, double extent_mm, double value_abs) {
    return period / (2 * M_PI) * gamma * std::ldexp(1.0, -(bits - 1)) * pixel_mm + decoded_position(extent_mm, value_abs);
}

// OMP's coefficients on the recovered support: the final least-squares fit by Householder QR is
// backward stable, so the coefficients are within c K u kappa(A_S) |t| of the exact ones (Higham,
// Accuracy and Stability, 2nd ed., Thm. 20.3, first order, c a small constant), z itself carrying
// s K u |t| from its double evaluation. With mutual coherence mu < 1 / (2 s - 1) the Gram matrix
// of the normalised support columns has eigenvalues in [1 - (s - 1) mu, 1 + (s - 1) mu]
// (Gershgorin), so kappa <= sqrt(3) for s >= 2; 64 K u |t|_max covers c = 16 and the rest.
inline double omp_coefficient(int K, double max_abs) { return 64.0 * K * (kEps / 2) * max_abs; }

// A noise-free radiance y = b s + (1 - b) sum_lit T (acquire/Acquisition.cpp) against the exact
// sum: the row's n float entries summed in double (n u S), two products and a sum (3 u S), S the
// row's absolute sum; 2^-40 S bounds it for n < 2^10 with margin.
inline double radiance_sum(double abs_sum) { return std::ldexp(abs_sum, -40); }

}  // namespace ltm::tol

namespace ltm::tol {

// acquire_acquisition: brute force keeps at most 0.01 false entries per row in expectation
// (acquire/Acquisition.cpp, kFalseEntriesPerRow), independently per measurement, so the false
// entries of R rows are at most Poisson(0.01 R) (a sum of independent rare Bernoullis is
// dominated by it, Le Cam). For R = 400, mean 4: P(N >= 15) = 2.0e-5 (the Poisson tail summed
// directly), so at most 14 are allowed.
constexpr int kBruteForceFalseEntries400Rows = 14;

}  // namespace ltm::tol

namespace ltm::tol {

// io_peak_rss: how far a stretch's measured RSS growth can lie from the pages it writes itself.
// Above: the allocator's arena growth, page tables (8 bytes per 4 KiB page: 16 KiB for 8 MiB),
// gtest's bookkeeping and /proc reads. Below: Linux counts RSS in per-CPU batches, so VmRSS and
// VmHWM lag the true count by up to a batch per CPU (measured here: 88 KiB short of 64 MiB
// written). A few MiB at most either way; 16 MiB bounds it with margin while staying far below
// the 64 MiB a stale, process-wide peak would add.
constexpr double kRssNoiseBytes = 16.0 * 1024 * 1024;

}  // namespace ltm::tol

namespace ltm::tol {

// geometry_lattice_phase: S's closed form (six B2 terms, |B2| <= 1/6, entries of m m^T <= 1)
// against its barycentric definition (four products l (v - xi)_i (v - xi)_j <= 1, the coordinates
// from 3x3 determinants of O(1) entries): ~20 roundings of O(1) terms on each side, and the
// fractional parts of m . xi for |xi| <= 3 lose 3 bits: 1e-13 is ~450 eps, with margin.
constexpr double kLatticeMomentAbs = 1e-13;
// Psi against the transport equation by central differences (exact for Psi and e, piecewise
// quadratic, away from the faces): what is left is rounding over the step, eps |m . xi| / (step / a)
// relative, |m . xi| <= 60 and step = 1e-3 a: 1.3e-11 relative to a ||H||; p . Psi = e / 2 to
// eps |m . xi| / |m . p|-ish relative, 1e-12. Both with margin: 1e-9 and 1e-11.
constexpr double kLatticeTransportRelative = 1e-9;
constexpr double kLatticeInvariantRelative = 1e-11;

}  // namespace ltm::tol

namespace ltm::tol {

// validation_tetwalk: a product target, not a rounding bound: display hits of a smooth inclusion
// meshed at the default index tolerance within 1e-3 mm of the converged reference (docs/grin.md,
// "Accuracy"; a tenth of a typical display pixel of 0.1..0.3 mm, so that T's columns do not move).
constexpr double kInclusionDisplayTarget = 1e-3;  // mm

}  // namespace ltm::tol

namespace ltm::tol {

// defects_inclusion: the Hessian of n^2 = (n0 + dn (1 - s)^2)^2 (degree 8 in x) against central
// second differences with the step h = 1e-4 e_min: the truncation is h^2 / 12 of the fourth
// derivatives, whose size is ~ 10^2 ||D^2 n^2|| / e_min^2 here, 1e-7 of the bound; the rounding
// is 4 eps n^2 / (4 h^2) = 1.2e-8 / e_min^2 mm^-2, 2e-7 of the bound (~0.1 mm^-2) for
// e_min = 0.8. 1e-5 of the bound, with margin. Identities (the Laplacian as the trace, the
// bound at a point) hold to rounding of O(10) terms: 1e-12.
constexpr double kFieldDifferenceStep = 1e-4;
constexpr double kFieldDifferenceRelative = 1e-5;
constexpr double kFieldIdentityRelative = 1e-12;

}  // namespace ltm::tol

namespace ltm::tol {

// Lens::farthest_distance against a closed form or a sampled distance (tests/geometry_lens.cpp):
// the antipode c - (p - c) |R| / |p - c| and its distance to p, or an edge circle's hypot, take at
// most 8 roundings, each relative to the magnitudes involved (<= M, the distance itself or the
// operands |p|, |R|): within 8 u M; 16 u M leaves a factor 2.
inline double farthest_point(double magnitude) { return 16.0 * (kEps / 2) * magnitude; }

}  // namespace ltm::tol
