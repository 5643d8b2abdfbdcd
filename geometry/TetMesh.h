#pragma once
// Tetrahedral meshes of the regions where the glass's index is neither constant nor a quadratic
// n^2 (smooth inhomogeneities; the linear-n field): TetGen fills a closed boundary surface with
// tetrahedra, refined until n^2 interpolated linearly over every tetrahedron is within a
// tolerance of the field. The tracer then follows exact parabolas through them (trace/TetWalk.h).
//
// TetGen (AGPL-3+) is a PRIVATE dependency of geometry/, like CGAL: only geometry/TetGen.cpp
// includes <tetgen.h>. Nothing here exposes a TetGen type.
//
// Interpolation error bound (Waldron, "The error in linear interpolation at the vertices of a
// simplex", SIAM J. Numer. Anal. 35, 1998): for f twice differentiable on a tetrahedron T with
// ||D^2 f||_2 <= M on T, |f - I f| <= M r^2 / 2 on T, where r is the radius of the smallest ball
// containing T. A tetrahedron is refined while M r^2 / 2 > tolerance, with M from the region's
// `hessian_bound` over that ball; so the bound holds everywhere in the mesh.
#include <array>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry/LatticePhase.h"
#include "geometry/StageReport.h"
#include "geometry/TriMesh.h"
#include "geometry/Vec3.h"

namespace ltm {

struct TetMesh {
    std::vector<Vec3> vertices;
    std::vector<double> n2;                           // per vertex: the field's n^2 there
    std::vector<std::array<std::uint32_t, 4>> tets;   // positively oriented: det(b-a, c-a, d-a) > 0
    // neighbors[t][i]: the tetrahedron across the face opposite vertex i of t, or -1 (the
    // boundary of the meshed region).
    std::vector<std::array<std::int32_t, 4>> neighbors;
    double error_bound = 0;      // the largest M r^2 / 2 over the tetrahedra (<= the tolerance)
    std::string name;            // the region's name, e.g. "defects[2]" or "object"
    // The lattice the interior was filled with, and the field's Hessian D^2 n^2, for the end
    // correction of paths entering and leaving it (LatticePhase.h); spacing 0 and empty when the
    // region gave no `hessian` or has no lattice.
    LatticeFrame lattice;
    std::function<Mat3(const Vec3&)> hessian;

    size_t num_tets() const { return tets.size(); }
    Aabb bounds() const;
};

// What to mesh. The boundary must enclose the whole region in which paths are traced through the
// field (a circumscribed surface: an inclusion's ellipsoid lies inside it).
struct TetRegion {
    std::string name;                      // names the region in errors: "defects[2]", "object"
    TriMesh boundary;                      // closed, outward, two-manifold, not self-intersecting
    std::function<double(const Vec3&)> n2; // the field
    // An upper bound on ||D^2 n^2||_2 over the ball (centre, radius); in general, any M for which
    // M radius^2 / 2 bounds the error of the interpolated vertex values against the field over a
    // tetrahedron with that enclosing ball (an inclusion's corrected values add to the Hessian
    // bound: defects/SolidBuilder.cpp).
    std::function<double(const Vec3& centre, double radius)> hessian_bound;
    double tolerance = 1e-4;               // on n^2: M r^2 / 2 <= tolerance in every tetrahedron
    // Clipping: false when the ball (centre, radius) certainly lies outside the part of the region
    // that paths can reach (outside the glass); those tetrahedra are dropped after meshing.
    std::function<bool(const Vec3& centre, double radius)> keep;
    size_t max_tets = 20'000'000;          // refuse (TetGenError) rather than exhaust memory
    // How deep a point lies inside the region (its distance from the region's boundary, positive
    // inside; any lower bound of it will do). With it, the interior is filled with a regular
    // lattice (see tetrahedralize); without it, TetGen's Delaunay refinement fills it alone.
    std::function<double(const Vec3&)> depth;
    // The Hessian bound the lattice is spaced for (lattice_spacing); 0: hessian_bound over the
    // ball around the boundary's bounding box. A region whose field only matters in part of it
    // (an inclusion's mesh is used inside its ellipsoid) gives the bound over that part.
    double lattice_hessian = 0;
    // The field's Hessian D^2 n^2 where paths use the mesh (at the handover to the exact glass),
    // for the lattice's end correction (LatticePhase.h); empty: paths are handed over uncorrected.
    std::function<Mat3(const Vec3&)> hessian;
};

// The lattice an interior is filled with: body-centred cubic, of cube edge `a`, turned by a fixed
// rotation. Why a lattice: piecewise-linear interpolation of a smooth field errs in its gradient
// by O(h M) (the field's curvature over a tetrahedron), and a path bends with that gradient. On
// an unstructured mesh the errors of the ~L/h tetrahedra a path crosses add like a random walk,
// O(h^1.5) in the end. On a lattice the gradient error is the same periodic function in every
// cell, and along a path that crosses the cells at a generic angle it averages out, leaving
// O(h^2) = O(tolerance). Three things decide the constant (docs/grin.md):
//  * the error's mean over a cell is not zero (a^2 tr(D^2 n^2) / 24 for BCC, a smooth bias
//    field); an inclusion's region takes it out of its vertex values (defects/SolidBuilder.cpp);
//  * a path nearly parallel to a low-order lattice plane does not average the periodic part: the
//    mode k of the error adds up as 1 / |k . d|. The rotation puts telecentric rays (along z) far
//    from every such plane: z in the lattice frame is d = (0.1146, 0.4419, 0.8897), which
//    minimises the resonance score of scripts/lattice-direction (9.14, at most 11.1 within 5
//    degrees of z; the rotation (37.3, 23.7, 11.1), for comparison, scores 11.4 and 14.9). The
//    rotation about z is immaterial for rays along z.
//  * a path enters and leaves the lattice at a phase of its own: the end terms, which the tracer
//    corrects in closed form (LatticePhase.h), given the lattice's frame and the field's Hessian.
// Measured for the 2.5 mm, delta_n = 0.02 inclusion of scenes/examples/inclusion-smooth.yaml at
// the tolerance 1e-4 (display 60 mm behind; rays on a 0.2 mm grid; bench/bench_grin.cpp e):
// unstructured, 1.9 million tetrahedra, display errors 0.018 mm at most, 0.0037 mm on average;
// the lattice without the bias correction, at the rotation (37.3, 23.7, 11.1), 2.0 million, 0.0054 and
// 0.0013 mm; with the correction (and the continued profile of defects/SolidBuilder.cpp) at this
// rotation, 2.5 million, 0.0016 and 0.00034 mm; with the end correction as well, 4.8e-5 and
// 1.1e-5 mm. BCC's Delaunay tetrahedra are congruent, with circumradius a sqrt(5) / 4, which is
// their smallest enclosing radius (the circumcentre lies inside), so a = 4 sqrt(2 t / M) / sqrt(5)
// meets the tolerance t where ||D^2 n^2|| <= M; lattice_spacing returns 0.9 of that, so that
// rounding never tips a lattice tetrahedron over the bound (a split would break the regularity
// locally).
inline constexpr double kLatticeAngles[3] = {26.41, -6.58, 0.0};  // degrees, rotation_from_euler_deg
double lattice_spacing(double tolerance, double hessian_bound);

// A TetGen failure (invalid input, an internal error code, or too many tetrahedra), reported with
// the region's name; never an abort.
struct TetGenError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Meshes the region (TetGen -pq with the refinement criterion above; with a `depth`, TetGen also
// inserts the lattice points at least 0.6 a inside, a = lattice_spacing(tolerance, the region's
// largest Hessian bound), so that only the layer along the boundary is left to its refinement),
// drops the tetrahedra that
// `keep` rejects, orients every tetrahedron positively and fills the neighbour list. Records a
// "tetgen" stage (time, tetrahedra, vertices, error bound) in the report. Throws TetGenError.
TetMesh tetrahedralize(const TetRegion& region, StageReport* report = nullptr);

// The radius of the smallest ball containing the four points (the circumsphere of 2, 3 or all 4
// of them), and its centre.
double smallest_enclosing_ball(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Vec3* centre);

}  // namespace ltm
