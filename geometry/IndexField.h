#pragma once
// The glass's refractive index as a field n(x) instead of one number (docs/scene-format.md,
// "object.index_field"). x is measured from the object's centre, the origin, in mm.
//
// The closed-form kinds are those whose n^2 is a quadratic polynomial in x; the ray equation in
// the parameter tau (d tau = ds / n, p = n dr/ds, |p| = n) is then linear,
//   dr/dtau = p,   dp/dtau = grad(n^2) / 2 = (b + H x) / 2,
// and its paths are closed form (trace/GrinPath.h):
//   linear_n2      n^2 = ior^2 + gradient . x                          b = gradient, H = 0
//   radial_n2      n^2 = ior^2 (1 - G^2 (x^2 + y^2))   (a GRIN rod)     b = 0, H = -2 ior^2 G^2 diag(1, 1, 0)
//   spherical_n2   n^2 = ior^2 (1 - g^2 |x|^2)        (Luneburg when ior = sqrt 2, g = 1 / (R sqrt 2))
//                                                                       b = 0, H = -2 ior^2 g^2 I
//   quadratic_n2   n^2 = ior^2 + gradient . x + x^T hessian x / 2       b = gradient, H = hessian
// One kind is meshed by TetGen over the whole object ON PURPOSE, its n^2 linear in each tetrahedron:
//   linear_n       n = ior + gradient . x
// Its exact rays are catenaries in the planes containing the gradient, which makes it the control
// case of the tetrahedral tracer (its O(h^2) convergence is tested against them). The same field
// in closed form is quadratic_n2 with gradient 2 ior g and hessian 2 g g^T.
#include <string>
#include <vector>

#include "geometry/Lens.h"
#include "geometry/Vec3.h"

namespace ltm {

enum class IndexFieldType { Uniform, LinearN2, RadialN2, SphericalN2, QuadraticN2, LinearN };
const char* to_string(IndexFieldType t);  // the scene-file name: "uniform", "linear_n2", ...

// n^2(x) = c + b . x + x^T H x / 2 (H symmetric).
struct QuadraticForm {
    double c = 0;
    Vec3 b;
    Mat3 H = Mat3::zero();
    double operator()(const Vec3& x) const { return c + dot(b, x) + 0.5 * dot(x, H * x); }
    Vec3 gradient(const Vec3& x) const { return b + H * x; }
};

struct IndexField {
    IndexFieldType type = IndexFieldType::Uniform;
    double ior = 1.5;               // n at the origin (equal to the object's ior)
    Vec3 gradient;                  // linear_n2, quadratic_n2: of n^2 (1/mm); linear_n: of n (1/mm)
    double g = 0;                   // radial_n2: G; spherical_n2: g (1/mm)
    Mat3 hessian = Mat3::zero();    // quadratic_n2: of n^2 (1/mm^2), symmetric

    bool graded() const { return type != IndexFieldType::Uniform; }
    // Traced in closed form (n^2 quadratic; Uniform included), not through a TetGen mesh.
    bool closed_form() const { return type != IndexFieldType::LinearN; }
    // The quadratic form of n^2. Precondition: closed_form().
    QuadraticForm n2_form() const;
    double n2(const Vec3& x) const;
    double n(const Vec3& x) const;
    Vec3 grad_n2(const Vec3& x) const;
};

// The range of a quadratic function over the lens solid (closed), found exactly: the global
// minimum and maximum of a smooth function over the solid are attained at a stationary point of
// its restriction to one of the solid's strata (the interior; the front and back caps, spheres or
// flat discs; the rim band; the two edge circles), so the extremes are the extremes over the
// finite set of those stationary points (Lagrange / KKT), each found in closed form or as a
// bracketed root of a secular equation. Continua of stationary points (where the function is
// constant along a circle or sphere) contribute their constant value when they meet the stratum.
struct QuadraticRange {
    double min = 0, max = 0;
    Vec3 argmin, argmax;
};
QuadraticRange quadratic_range(const Lens& lens, const QuadraticForm& q);

// The range of n^2 over the solid: exact for the closed-form kinds (quadratic_range), and for
// linear_n from the exact range of the linear n.
struct IndexRange {
    double n2_min = 0, n2_max = 0;
    double n_min = 0, n_max = 0;    // sqrt of the above (0 where n^2 <= 0)
    Vec3 argmin;                    // where n^2 is smallest
};
IndexRange index_range(const Lens& lens, const IndexField& field);

// n may fall this far below 1 before a field is rejected: a field typed with ~16 significant
// digits (the Luneburg sphere's g = 1 / (R sqrt 2) = 0.0707106781186548) rounds n^2 at its surface
// to 1 - O(1e-15), and a user's 12-digit constants to 1 - O(1e-12); 1e-9 keeps every such field
// and rejects any that is physically below vacuum.
inline constexpr double kIndexBelowOneSlack = 1e-9;

// Why a field is not a valid glass over this object, as (key, message) pairs; `key` is relative
// to the index_field mapping ("type", "g", "gradient", "hessian", or "" for the mapping itself).
// Checks: finite parameters; a symmetric hessian; n^2 > 0 and n >= 1 - kIndexBelowOneSlack
// everywhere in the solid (index_range).
struct IndexFieldProblem {
    std::string key, message;
};
std::vector<IndexFieldProblem> index_field_problems(const Lens& lens, const IndexField& field);

}  // namespace ltm
