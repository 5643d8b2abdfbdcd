#pragma once
// Paths through a TetGen-meshed index field (geometry/TetMesh.h): n^2 is linear in each
// tetrahedron T, n^2(x) = n2_T + g_T . (x - v_T), so the ray equation (GrinPath.h) has a constant
// right-hand side there and the path is an exact parabola,
//   r(tau) = r + p tau + g_T tau^2 / 4,    p(tau) = p + g_T tau / 2,
// and |p|^2 - n^2(r) stays constant (both change by g.p tau + |g|^2 tau^2 / 4).
//
// Exit face: the plane of a face is s(x) = n_f . x - o_f, with n_f and o_f computed ONCE per face
// from its three vertices in ascending index order, so the two tetrahedra sharing a face use
// bit-identical coefficients and opposite signs: a path leaving one through a face is inside the
// other by the same rounding, never in both or in neither. Along the parabola,
//   s(r(tau)) = s(r) + (n_f . p) tau + (n_f . g_T / 4) tau^2,
// a quadratic solved with the stable formula; the face a path came in through has s = 0 at
// tau = 0 exactly, so only its other root -b / a counts (a path that curves back through it).
// A face whose plane the point is already on or beyond (an edge or vertex hit) is left at tau = 0
// if the path moves out through it: the walk passes through the tetrahedra around an edge or a
// vertex in zero-length steps, bounded by trace_tol::kWalkMaxZeroSteps.
//
// The exact surfaces a path can meet inside the region (the inclusion's own ellipsoid, where it
// hands over to the glass; the object's faces where the region reaches them; enclosed defects)
// are listed per tetrahedron (those whose surface passes within the tetrahedron's enclosing
// ball) and solved on the parabola as quartics (trace/Polynomial.h), before the exit face.
//
// Where the mesh is a lattice, the path's momentum is handed over with the lattice's end
// correction (entering, leaving; geometry/LatticePhase.h): the mesh's periodic interpolation error
// drives an oscillating part of the momentum, which a path coming from outside lacks.
#include <cstdint>
#include <memory>
#include <vector>

#include "geometry/TetMesh.h"
#include "trace/GrinPath.h"
#include "trace/Patch.h"

namespace ltm {

class TetWalk {
public:
    // `surfaces`: the exact surfaces paths in this region can meet (Patch::tag names them).
    TetWalk(const TetMesh& mesh, std::vector<Patch> surfaces);
    ~TetWalk();

    // The tetrahedron containing x (barycentric coordinates >= -kLocateSlack), or -1.
    int locate(const Vec3& x) const;
    // n^2 interpolated in tetrahedron t.
    double n2(int t, const Vec3& x) const;
    const std::vector<Patch>& surfaces() const { return surfaces_; }
    size_t num_tets() const { return tets_.size(); }

    struct Exit {
        enum class Kind { Surface, Boundary, Stuck } kind = Kind::Stuck;
        Vec3 r, p;          // where and with what momentum the path leaves
        int tet = -1;       // the tetrahedron it was in
        int surface = -1;   // Kind::Surface: index into surfaces()
        double tau = 0;     // total parameter
        double arc = 0;     // arc length (when asked)
        long crossings = 0; // tetrahedra left
    };
    // Walks from (r, p) in tetrahedron `tet` until the path meets an exact surface or leaves the
    // meshed region. With `arc`, accumulates the arc length (3-point Gauss-Legendre per
    // tetrahedron: |p| = sqrt of a quadratic in tau, smooth over one tetrahedron).
    Exit walk(const Vec3& r, const Vec3& p, int tet, bool arc) const;

    // The lattice's end correction (geometry/LatticePhase.h): the momentum a path arriving at r
    // with the true momentum p carries into the mesh (p + Psi, rescaled to |p|), and the true
    // momentum of a path that leaves the mesh at r with p (p - Psi). The identity where the mesh
    // has no lattice or no Hessian.
    Vec3 entering(const Vec3& r, const Vec3& p) const;
    Vec3 leaving(const Vec3& r, const Vec3& p) const;

private:
    // A face plane, oriented so that it is positive inside the tetrahedron that stores it: n . x - o.
    // The two tetrahedra sharing a face store bit-identical copies of opposite sign (negation is
    // exact in floating point), computed once from the face's vertices in ascending index order.
    struct Plane {
        Vec3 n;
        double o = 0;
    };
    // Everything a crossing reads, in one block: one memory access per tetrahedron entered.
    struct Tet {
        Plane plane[4];             // plane[i]: the face opposite vertex i
        Vec3 g, v0;                 // n^2 = n2_0 + g . (x - v0)
        double n2_0 = 0;
        std::int32_t next[4];       // the neighbour across face i, or -1
        std::uint8_t next_face[4];  // the index of the shared face in the neighbour
        std::uint32_t surf_begin = 0, surf_count = 0;
    };
    double face_value(const Tet& t, int i, const Vec3& x) const { return dot(t.plane[i].n, x) - t.plane[i].o; }
    std::vector<Tet> tets_;          // in Morton order of their centroids: neighbours lie close in memory
    std::vector<std::array<double, 4>> inv_height_;  // per tetrahedron: 1 / (face value at the opposite vertex)
    std::vector<std::uint32_t> tet_surfaces_;  // per tetrahedron, indices into surfaces_
    std::vector<Patch> surfaces_;
    std::vector<Quadric> quadrics_;
    LatticePhase phase_;
    std::function<Mat3(const Vec3&)> hessian_;
    // Point location: a uniform grid of cells listing the tetrahedra whose boxes meet them.
    Aabb grid_box_;
    int nx_ = 1, ny_ = 1, nz_ = 1;
    Vec3 cell_;
    std::vector<std::uint32_t> cell_begin_, cell_tets_;
};

}  // namespace ltm
