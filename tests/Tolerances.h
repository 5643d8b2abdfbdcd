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

// Exported mesh files (geometry/MeshExport.h) hold float32 coordinates: OpenMesh rounds each double
// to the nearest float when writing (ASCII is printed with 9 significant digits, float's
// max_digits10, so it holds the same float). Rounding to nearest binary32 moves x by at most half
// an ulp, i.e. the unit roundoff 2^-24 relative: |float(x) - x| <= 2^-24 |x| <= 2^-24 L for
// coordinates of magnitude at most L.
inline double float_export(double scale) { return std::ldexp(scale, -24); }

// Rec. 709 luminance of a float RGB pixel (features/Image.h, pattern_values): the code evaluates
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
