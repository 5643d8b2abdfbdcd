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

}  // namespace ltm::tol
