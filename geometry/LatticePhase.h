#pragma once
// The periodic part of the lattice's interpolation error, and the momentum a path carries because
// of it where it enters and leaves a lattice-meshed field (geometry/TetMesh.h, trace/TetWalk.h).
//
// The error. On the BCC lattice of cube edge a, linear interpolation of a field with Hessian H
// (locally constant on the scale of a) errs by
//   e(x) = I n^2 - n^2 = tr(H (S(xi) - I / 12)) a^2 / 2,
//   S(xi) = sum_v l_v (v - xi)(v - xi)^T   (xi = x / a in the lattice frame, cube corners at
//   integers; l_v the barycentric coordinates of xi in its tetrahedron, v its vertices),
// where I / 12 is S's mean, which an inclusion's vertex values already take out
// (defects/SolidBuilder.cpp). BCC's Delaunay tetrahedra are the cells of the six plane families
// m . xi in Z, m in D = {(1, +-1, 0), (1, 0, +-1), (0, 1, +-1)}, so S is a sum of one-dimensional
// periodic functions of those coordinates. In closed form (bcc_interpolation_moment):
//   S(xi) = I / 12 + (1/4) sum_{m in D} (e_m e_m^T - m m^T) B2({m . xi}),
// with e_m the axis orthogonal to m, {t} the fractional part and B2(t) = t^2 - t + 1/6 the
// Bernoulli polynomial, whose Fourier series is sum_{j >= 1} cos(2 pi j t) / (pi^2 j^2). It is
// piecewise quadratic with kinks on the faces, zero at every vertex (sum_D (e_m e_m^T - m m^T) =
// 2 I - 4 I), and tests/geometry_lattice_phase.cpp checks it against the barycentric definition
// and against a TetGen mesh's own interpolation.
//
// The momentum. The ray equation dp/dtau = grad(n^2 + e) / 2 splits, to first order in the
// error and for a field slowly varying against a, into the true path's momentum pbar and an
// oscillating part that is a function of position, p = pbar + Psi(x), with (p . grad) Psi =
// grad e / 2 (the mode exp(2 pi i j m . xi) of e gives j m / (j m . p) times itself in Psi).
// Summed over j with B2's series, for each family:
//   Psi(x) = (a^2 / 16) sum_{m in D} m (H_mm - m^T H m) B2({m . xi}) / (m . p)
// in the lattice frame (H_mm = e_m^T H e_m). A path that enters the lattice with the true
// momentum therefore drifts by -Psi(entry) for the whole of its way through and leaves with
// +Psi(exit) on top: an end term of the size of the error's gradient times a period over
// |m . d|, independent of the path's length, which no refinement along the path removes. Handing
// over p + Psi at entry and p - Psi at exit removes it, leaving O(a^2 |grad H| L) and the
// second-order terms. Psi . p = e / 2: the correction also restores |p|^2 = n^2 + e, the mesh's
// invariant, to first order.
//
// A family nearly parallel to the path (|m . p| < kResonance |m| |p|) is left out: along the path
// its planes barely alternate, the expansion does not hold for it, and what it contributes is
// secular, not an end term. (The lattice's rotation keeps telecentric rays at |m . d| / |m| >=
// 0.23 from all six: TetMesh.h.)
#include "geometry/Vec3.h"

namespace ltm {

// Where the lattice lies: world x = rotation (origin + a xi); xi integer at cube corners.
struct LatticeFrame {
    Mat3 rotation = Mat3::identity();  // lattice frame -> world
    Vec3 origin;                       // a cube corner, in the lattice frame (mm)
    double spacing = 0;                // a; 0: the mesh has no lattice
};

// S(xi) in cube units, the closed form above.
Mat3 bcc_interpolation_moment(const Vec3& xi);

class LatticePhase {
public:
    static constexpr double kResonance = 0.05;

    explicit LatticePhase(const LatticeFrame& frame);

    // Psi at x (world) for a path with momentum p (world, |p| = n) in a field whose Hessian of
    // n^2 is `hessian` (world) there. Zero where there is no lattice.
    Vec3 operator()(const Vec3& x, const Vec3& p, const Mat3& hessian) const;

private:
    LatticeFrame frame_;
    Mat3 to_lattice_;  // rotation^T
};

}  // namespace ltm
