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
