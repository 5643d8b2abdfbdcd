// TetGen behind geometry/TetMesh.h. The only translation unit that includes <tetgen.h> (TetGen
// 1.5.0, Debian's libtet1.5-dev, AGPL-3+); nothing TetGen-specific leaves this file.
//
// What this file relies on, measured with this TetGen build (tests/geometry_tetmesh.cpp checks
// the parts that reach the TetMesh):
//   * tetrahedralize(char* switches, ...) takes a writable switch string;
//   * failures are thrown as a plain int (terminatetetgen, with TETLIBRARY), codes listed in
//     tetgen_failure below;
//   * TetGen's assertions are compiled in, and bad input crashes the process instead of raising
//     an error: a self-intersecting boundary with -p ended in a segmentation fault. So the
//     boundary is checked here first (checked_boundary), and TetGen only ever sees a closed,
//     outward, two-manifold, self-intersection-free surface without degenerate faces;
//   * tetgenio::tetunsuitable is called (with -q, without -u, which this build rejects as an
//     unknown switch) for every tetrahedron TetGen creates while refining, with its four corners,
//     a null edge-length array and a zero volume; TetGen splits those for which it returns true;
//   * TetGen declines to split some of the tetrahedra the callback calls unsuitable, and its
//     mesh optimisation (on by default, -O) changes tetrahedra after the callback has passed
//     them; so the criterion is checked again on TetGen's output, and what fails is bisected here
//     (Bisection below);
//   * with -n -z the output neighbour list holds, for tetrahedron t, in slot i the tetrahedron
//     across the face opposite corner i, and -1 on the boundary; every output tetrahedron had
//     det(b - a, c - a, d - a) > 0. Neither is taken on trust: slots are recomputed from the
//     shared vertices (raw_mesh), orientation from the determinant (tetrahedralize).
#include "geometry/TetMesh.h"

#ifndef TETLIBRARY
// libtet.so is built with TETLIBRARY, and tetgen.h differs without it: the char* overload of
// tetrahedralize is only declared with it, and the inline terminatetetgen would call exit()
// instead of throwing. CMakeLists.txt defines it for ltm_geometry.
#error "geometry/TetGen.cpp must be compiled with TETLIBRARY defined (see CMakeLists.txt)"
#endif
#include <tetgen.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <exception>
#include <mutex>
#include <new>
#include <numeric>
#include <tuple>
#include <unordered_map>
#include <utility>

#include <fmt/format.h>

#include "geometry/Boolean.h"

namespace ltm {

Aabb TetMesh::bounds() const {
    Aabb b;
    for (const Vec3& v : vertices) b.extend(v);
    return b;
}

namespace {

// The switches, chosen by measurement (sphere of radius 2.5 mm with the smooth profile field of
// bench/bench_tetgen.cpp, and the lens of tests/geometry_tetmesh.cpp):
//   p     the input is a piecewise linear complex (our boundary): mesh its inside;
//   q1.4  Delaunay refinement to radius-edge ratio <= 1.4 (TetGen's default is 2.0). -q is what
//         makes TetGen call tetunsuitable; 1.4 makes 0.1% more tetrahedra than 2.0 in the same
//         time (1.14e6 at 1e-4), with the largest radius-edge ratio 5.4 instead of 6.2;
//   M     no merging of nearly coplanar input triangles: by default TetGen treats neighbouring
//         triangles within 0.1 degree of coplanar as one facet and retriangulates it, which moves
//         the boundary of a lens (whose caps are nearly flat near the axis) and changes the meshed
//         volume by 1e-4 mm^3 of 264; with -M every input triangle stays on the boundary (the
//         volume agrees to rounding), at 15% more tetrahedra for that lens and none more for
//         spheres. Very close vertices are not merged either; checked_boundary rejects them;
//   n     output the neighbour list;  z  number everything from zero;  Q  quiet;
//   S#    the Steiner point budget that enforces max_tets (kTetsPerSteinerPoint), appended.
// TetGen's default mesh optimisation (-O2/7: flips, smoothing, vertex insertion and deletion) stays on: without it
// (-O0) the same meshes have dihedral angles down to 0.06 degrees (slivers), with it none below
// 6 degrees, at the same count and 20% more time; the few tetrahedra it pushes back above the
// tolerance are bisected afterwards.
// Not -Y: the boundary triangles must be split where the criterion asks for tetrahedra smaller
// than them (a tetrahedron on a boundary triangle is at least as big as the triangle's
// circumscribed circle). TetGen's Steiner points lie on the input triangles (flat), so the
// meshed region is still the one the boundary encloses.
constexpr const char* kSwitches = "pq1.4MnzQ";

// Relative size below which the boundary is degenerate: TetGen's own tolerance for its coplanarity
// tests (-T) is 1e-8 relative, so features smaller than that are noise to it. A face whose height
// is below that fraction of its longest edge counts as having zero area, two vertices closer than
// that fraction of the bounding box's diagonal as duplicates.
constexpr double kRelativeTolerance = 1e-8;

// max_tets is enforced inside TetGen by its Steiner point budget (-S): refinement stops, cleanly,
// once that many points were added. Each point added to a tetrahedral mesh adds several
// tetrahedra (measured: 5.4 to 17 tetrahedra per Steiner point on spheres and lenses; about 6 in
// the interior of any Delaunay mesh), so a budget of max_tets / 3 never stops a mesh that ends
// within max_tets, and a mesh that exhausts it (and is refused) has about 2 max_tets tetrahedra.
// Merely answering false in the callback does not stop TetGen soon enough: measured at the
// tolerance 1e-5 of bench/bench_tetgen.cpp, it goes on from 1.3e7 to 3.0e7 tetrahedra (6 GB)
// working through the splits already queued.
constexpr double kTetsPerSteinerPoint = 3;

// TetGen keeps process-wide state: exactinit() sets the static filters of its orientation and
// insphere predicates from the bounding box of each call (and its lookup tables are statics), so
// two concurrent calls would use each other's filters. Calls are serialised.
std::mutex g_tetgen_mutex;

[[noreturn]] void fail(const TetRegion& region, const std::string& why) {
    throw TetGenError(fmt::format("cannot mesh {}: {}", region.name, why));
}

std::string point_text(const Vec3& p) { return fmt::format("({:.9g}, {:.9g}, {:.9g})", p.x, p.y, p.z); }

// ---- the error criterion ---------------------------------------------------------------------

// The interpolation error bound of one tetrahedron: M r^2 / 2 with r the radius of its smallest
// enclosing ball and M the region's Hessian bound over that ball (which contains the tetrahedron).
struct TetError {
    Vec3 centre;
    double radius = 0;
    double hessian = 0;
    double error = 0;
    bool valid() const { return std::isfinite(hessian) && hessian >= 0; }
};

TetError tet_error(const TetRegion& region, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    TetError e;
    e.radius = smallest_enclosing_ball(a, b, c, d, &e.centre);
    e.hessian = region.hessian_bound(e.centre, e.radius);
    e.error = 0.5 * e.hessian * e.radius * e.radius;
    return e;
}

std::string invalid_hessian_text(const TetError& e) {
    return fmt::format("hessian_bound returned {} over the ball centred {} of radius {:.9g} "
                       "(it must be a finite number >= 0)",
                       e.hessian, point_text(e.centre), e.radius);
}

// ---- the refinement callback -------------------------------------------------------------------

// What the callback needs and what it found. tetunsuitable has no user-data argument, so the
// callback finds this through a thread_local pointer, set for the duration of one TetGen call on
// this thread (TetGen runs the callback on the calling thread).
struct Refinement {
    const TetRegion* region = nullptr;
    std::string invalid;       // hessian_bound returned something unusable
    std::exception_ptr error;  // hessian_bound threw
    bool failed() const { return !invalid.empty() || error; }
};

thread_local Refinement* t_refinement = nullptr;

Vec3 point_of(const REAL* p) { return {p[0], p[1], p[2]}; }

// TetGen's tetunsuitable: true when the tetrahedron must be split. Nothing is thrown through
// TetGen: unwinding out of it leaked memory (measured: ~10 MB per abandoned 70k-tetrahedron
// mesh, repeatedly), as TetGen frees some of its refinement's work space only on its normal path.
// A failure of hessian_bound is recorded and answered by false from then on, which lets TetGen
// finish the splits it has queued (within the Steiner point budget, kTetsPerSteinerPoint);
// tetrahedralize reports the failure after TetGen returns.
bool tet_unsuitable(REAL* pa, REAL* pb, REAL* pc, REAL* pd, REAL* /*edge lengths: null*/,
                    REAL /*volume: 0*/) noexcept {
    Refinement& r = *t_refinement;
    if (r.failed()) return false;
    try {
        const TetError e = tet_error(*r.region, point_of(pa), point_of(pb), point_of(pc), point_of(pd));
        if (!e.valid()) {
            r.invalid = invalid_hessian_text(e);
            return false;
        }
        return e.error > r.region->tolerance;
    } catch (...) {
        r.error = std::current_exception();
        return false;
    }
}

// Sets t_refinement for one TetGen call and clears it however the call ends.
class RefinementScope {
public:
    explicit RefinementScope(Refinement* r) { t_refinement = r; }
    ~RefinementScope() { t_refinement = nullptr; }
    RefinementScope(const RefinementScope&) = delete;
    RefinementScope& operator=(const RefinementScope&) = delete;
};

// ---- the boundary ---------------------------------------------------------------------------------

// The boundary as TetGen gets it: only the vertices some triangle uses (renumbered in order),
// so stray vertices of the TriMesh do not become isolated points of the mesh.
struct Boundary {
    std::vector<Vec3> points;
    std::vector<std::array<int, 3>> faces;
    std::vector<std::uint32_t> original;  // per point: its index in region.boundary.vertices
};

std::uint64_t edge_key(int a, int b) {
    const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
    return lo << 32 | hi;
}

int find_root(std::vector<int>& parent, int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

// Checks everything TetGen needs of a boundary, in an order where each check may rely on the
// previous ones (finite coordinates before distances, faces before edges, edges before volumes),
// and returns it in TetGen's terms. Throws TetGenError naming the region and the first problem.
Boundary checked_boundary(const TetRegion& region) {
    const TriMesh& m = region.boundary;
    const size_t nv = m.vertices.size();
    if (m.triangles.empty()) fail(region, "the boundary is empty (it has no triangles)");
    if (nv > static_cast<size_t>(INT_MAX) || m.triangles.size() > static_cast<size_t>(INT_MAX) / 3)
        fail(region, fmt::format("the boundary is too large for TetGen ({} vertices, {} triangles; its indices are int)",
                                 nv, m.triangles.size()));

    Boundary b;
    std::vector<int> id(nv, -1);
    b.faces.reserve(m.triangles.size());
    for (size_t f = 0; f < m.triangles.size(); ++f) {
        const auto& t = m.triangles[f];
        for (auto v : t)
            if (v >= nv) fail(region, fmt::format("triangle {} uses vertex {}, but the boundary has {} vertices", f, v, nv));
        if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
            fail(region, fmt::format("triangle {} ({}, {}, {}) repeats a vertex", f, t[0], t[1], t[2]));
        std::array<int, 3> face{};
        for (int k = 0; k < 3; ++k) {
            int& v = id[t[k]];
            if (v < 0) {
                v = static_cast<int>(b.points.size());
                if (!is_finite(m.vertices[t[k]]))
                    fail(region, fmt::format("vertex {} has a non-finite coordinate {}", t[k], point_text(m.vertices[t[k]])));
                b.points.push_back(m.vertices[t[k]]);
                b.original.push_back(t[k]);
            }
            face[k] = v;
        }
        b.faces.push_back(face);
    }
    const auto& P = b.points;
    const auto& F = b.faces;

    // Degenerate faces: |(b - a) x (c - a)| = 2 area = longest edge x height.
    for (size_t f = 0; f < F.size(); ++f) {
        const Vec3 &p = P[F[f][0]], &q = P[F[f][1]], &r = P[F[f][2]];
        const double longest2 = std::max({length2(q - p), length2(r - q), length2(p - r)});
        if (length(cross(q - p, r - p)) <= kRelativeTolerance * longest2)
            fail(region, fmt::format("triangle {} is degenerate: its height is below {:g} of its longest edge "
                                     "(vertices {}, {}, {})",
                                     f, kRelativeTolerance, point_text(p), point_text(q), point_text(r)));
    }

    // Duplicate vertices: closer than kRelativeTolerance x the bounding box's diagonal. Points are
    // binned into cubes of that size; a pair that close lies in the same or adjacent cubes.
    {
        Aabb box;
        for (const Vec3& p : P) box.extend(p);
        const double delta = kRelativeTolerance * length(box.hi - box.lo);
        struct CellHash {
            size_t operator()(const std::array<std::int64_t, 3>& c) const {
                const auto u = [&](int k) { return static_cast<std::uint64_t>(c[k]); };
                return static_cast<size_t>(u(0) * 73856093u ^ u(1) * 19349663u ^ u(2) * 83492791u);
            }
        };
        std::unordered_map<std::array<std::int64_t, 3>, std::vector<int>, CellHash> cells;
        cells.reserve(P.size());
        auto cell_of = [&](const Vec3& p) {
            return std::array<std::int64_t, 3>{static_cast<std::int64_t>(std::floor((p.x - box.lo.x) / delta)),
                                               static_cast<std::int64_t>(std::floor((p.y - box.lo.y) / delta)),
                                               static_cast<std::int64_t>(std::floor((p.z - box.lo.z) / delta))};
        };
        for (int i = 0; i < static_cast<int>(P.size()); ++i) {
            const auto c = cell_of(P[i]);
            for (std::int64_t dx = -1; dx <= 1; ++dx)
                for (std::int64_t dy = -1; dy <= 1; ++dy)
                    for (std::int64_t dz = -1; dz <= 1; ++dz) {
                        const auto it = cells.find({c[0] + dx, c[1] + dy, c[2] + dz});
                        if (it == cells.end()) continue;
                        for (int j : it->second)
                            if (distance(P[i], P[j]) <= delta)
                                fail(region, fmt::format("vertices {} and {} coincide: {} and {} are {:.3g} apart, "
                                                         "below {:g} of the bounding box's diagonal",
                                                         b.original[j], b.original[i], point_text(P[j]),
                                                         point_text(P[i]), distance(P[i], P[j]), kRelativeTolerance));
                    }
            cells[c].push_back(i);
        }
    }

    // Duplicate faces: the same three vertices, in either orientation.
    {
        std::vector<std::pair<std::array<int, 3>, size_t>> sorted(F.size());
        for (size_t f = 0; f < F.size(); ++f) {
            auto t = F[f];
            std::sort(t.begin(), t.end());
            sorted[f] = {t, f};
        }
        std::sort(sorted.begin(), sorted.end());
        for (size_t k = 1; k < sorted.size(); ++k)
            if (sorted[k].first == sorted[k - 1].first)
                fail(region, fmt::format("triangles {} and {} have the same three vertices", sorted[k - 1].second,
                                         sorted[k].second));
    }

    // Edges: closed, two-manifold and consistently oriented exactly when every edge is used by two
    // faces, once in each direction. Faces sharing an edge are joined into components.
    std::vector<int> parent(F.size());
    std::iota(parent.begin(), parent.end(), 0);
    {
        struct Use {
            int forward = 0, backward = 0;  // uses from the lower to the higher index, and back
            int face = -1;                  // the first face seen
        };
        std::unordered_map<std::uint64_t, Use> edges;
        edges.reserve(F.size() * 3 / 2 + 1);
        for (int f = 0; f < static_cast<int>(F.size()); ++f)
            for (int k = 0; k < 3; ++k) {
                const int a = F[f][k], c = F[f][(k + 1) % 3];
                Use& u = edges[edge_key(a, c)];
                (a < c ? u.forward : u.backward) += 1;
                if (u.face < 0) u.face = f;
                else parent[find_root(parent, f)] = find_root(parent, u.face);
            }
        for (const auto& [key, u] : edges) {
            const auto lo = b.original[key >> 32], hi = b.original[key & 0xffffffffu];
            const int uses = u.forward + u.backward;
            if (uses == 1)
                fail(region, fmt::format("the boundary is open: edge ({}, {}) belongs to triangle {} only", lo, hi,
                                         u.face));
            if (uses > 2)
                fail(region, fmt::format("the boundary is not two-manifold: edge ({}, {}) belongs to {} triangles", lo,
                                         hi, uses));
            if (u.forward != 1)
                fail(region, fmt::format("the boundary is not consistently oriented: the two triangles at edge ({}, {}) "
                                         "run through it in the same direction",
                                         lo, hi));
        }
    }

    // Every component must enclose a positive volume (outward faces): sum of det(a, b, c) / 6 over
    // its faces, about the bounding box's centre to keep the products small.
    {
        Aabb box;
        for (const Vec3& p : P) box.extend(p);
        const Vec3 o = (box.lo + box.hi) * 0.5;
        std::unordered_map<int, std::pair<double, size_t>> volume;  // root -> (volume, faces)
        for (int f = 0; f < static_cast<int>(F.size()); ++f) {
            auto& v = volume[find_root(parent, f)];
            v.first += dot(P[F[f][0]] - o, cross(P[F[f][1]] - o, P[F[f][2]] - o)) / 6.0;
            v.second += 1;
        }
        for (const auto& [root, v] : volume)
            if (!(v.first > 0))
                fail(region, fmt::format("the boundary is not outward: its component of {} triangles (triangle {} among "
                                         "them) encloses the signed volume {:.6g}",
                                         v.second, root, v.first));
    }

    // Non-manifold vertices and self-intersections, through CGAL (geometry/MeshCheck.cpp): TetGen
    // crashes on a self-intersecting boundary.
    TriMesh compact;
    compact.vertices = P;
    for (const auto& t : F)
        compact.add_triangle(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]),
                             static_cast<std::uint32_t>(t[2]), 0);
    const SolidCheck check = check_solid(compact);
    if (!check.valid_input || check.non_manifold_vertices > 0)
        fail(region, fmt::format("the boundary is not two-manifold: {} vertices are not (the triangles around each "
                                 "must form a single fan)",
                                 std::max<size_t>(check.non_manifold_vertices, 1)));
    if (check.self_intersecting) fail(region, "the boundary intersects itself");
    return b;
}

// ---- TetGen ---------------------------------------------------------------------------------------

std::string tetgen_failure(int code) {
    switch (code) {
        case 1: return "TetGen ran out of memory (code 1)";
        case 2: return "TetGen reported an internal error (code 2)";
        case 3: return "TetGen found a self-intersection of the boundary (code 3)";
        case 4: return "TetGen found an input feature too small for its tolerance (code 4)";
        case 5: return "TetGen found two boundary faces too close to each other (code 5)";
        case 10: return "TetGen found an input error (code 10)";
        default: return fmt::format("TetGen failed with code {}", code);
    }
}

// Fills TetGen's input. tetgenio's destructor frees every list with delete[], so they are
// allocated with new[].
void fill_input(const Boundary& b, tetgenio& in) {
    in.firstnumber = 0;
    in.numberofpoints = static_cast<int>(b.points.size());
    in.pointlist = new REAL[3 * b.points.size()];
    for (size_t i = 0; i < b.points.size(); ++i)
        for (int k = 0; k < 3; ++k) in.pointlist[3 * i + k] = b.points[i][k];
    in.numberoffacets = static_cast<int>(b.faces.size());
    in.facetlist = new tetgenio::facet[b.faces.size()];
    for (size_t f = 0; f < b.faces.size(); ++f) {
        tetgenio::facet& facet = in.facetlist[f];
        tetgenio::init(&facet);
        facet.numberofpolygons = 1;
        facet.polygonlist = new tetgenio::polygon[1];
        tetgenio::init(&facet.polygonlist[0]);
        facet.polygonlist[0].numberofvertices = 3;
        facet.polygonlist[0].vertexlist = new int[3];
        for (int k = 0; k < 3; ++k) facet.polygonlist[0].vertexlist[k] = b.faces[f][k];
    }
    in.tetunsuitable = tet_unsuitable;
}

// A tetrahedral mesh while it is being built: TetGen's output, then refined by bisection, before
// orientation and clipping. neighbors[t][i] is the tetrahedron across the face opposite vertex i.
struct RawMesh {
    std::vector<Vec3> vertices;
    std::vector<std::array<std::uint32_t, 4>> tets;
    std::vector<std::array<std::int32_t, 4>> neighbors;
    LatticeFrame lattice;  // spacing 0 without a lattice
};

RawMesh raw_mesh(const TetRegion& region, const tetgenio& out) {
    RawMesh r;
    if (out.numberofcorners != 4) fail(region, fmt::format("TetGen returned {}-node tetrahedra", out.numberofcorners));
    const auto np = static_cast<size_t>(out.numberofpoints), nt = static_cast<size_t>(out.numberoftetrahedra);
    r.vertices.resize(np);
    for (size_t i = 0; i < np; ++i) r.vertices[i] = point_of(&out.pointlist[3 * i]);
    r.tets.resize(nt);
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 4; ++k) {
            const int i = out.tetrahedronlist[4 * t + k];
            if (i < 0 || static_cast<size_t>(i) >= np)
                fail(region, fmt::format("TetGen's tetrahedron {} uses vertex {} of {}", t, i, np));
            r.tets[t][k] = static_cast<std::uint32_t>(i);
        }
    // Slot i of t: the neighbour that has every vertex of t but vertex i. Derived from the shared
    // vertices, so it holds whatever order TetGen lists the neighbours in.
    r.neighbors.assign(nt, {-1, -1, -1, -1});
    for (size_t t = 0; t < nt; ++t) {
        const auto& v = r.tets[t];
        for (int j = 0; j < 4; ++j) {
            const int n = out.neighborlist[4 * t + j];
            if (n < 0) continue;
            if (static_cast<size_t>(n) >= nt)
                fail(region, fmt::format("TetGen's tetrahedron {} has neighbour {} of {}", t, n, nt));
            const auto& w = r.tets[static_cast<size_t>(n)];
            int missing = -1, shared = 0;
            for (int i = 0; i < 4; ++i) {
                if (std::find(w.begin(), w.end(), v[i]) != w.end()) ++shared;
                else missing = i;
            }
            if (shared != 3 || r.neighbors[t][missing] != -1)
                fail(region, fmt::format("TetGen's tetrahedra {} and {} are listed as neighbours but do not share "
                                         "exactly one face",
                                         t, n));
            r.neighbors[t][missing] = n;
        }
    }
    return r;
}

// The rotated BCC lattice points at least 0.6 a deep in the region (TetMesh.h, lattice_spacing):
// the corners of the cubes of edge a and their centres, in the lattice's own frame R^T x, over
// the boundary's bounding box; `frame` says where it lies (LatticePhase.h).
std::vector<Vec3> lattice_points(const TetRegion& region, const Boundary& b, double a, LatticeFrame* frame) {
    std::vector<Vec3> out;
    if (!region.depth || !(a > 0)) return out;
    const Mat3 R = rotation_from_euler_deg({kLatticeAngles[0], kLatticeAngles[1], kLatticeAngles[2]});
    const Mat3 Rt = R.transposed();
    Aabb box;  // the boundary's box in the lattice frame
    for (const Vec3& p : b.points) box.extend(Rt * p);
    const double margin = 0.6 * a;
    const double cells = (box.hi.x - box.lo.x) * (box.hi.y - box.lo.y) * (box.hi.z - box.lo.z) / (a * a * a);
    if (!(2.0 * cells < static_cast<double>(region.max_tets)))
        fail(region, fmt::format("the lattice of spacing {:.3g} mm for the tolerance {:g} on n^2 would exceed max_tets "
                                 "= {} tetrahedra",
                                 a, region.tolerance, region.max_tets));
    const int nx = static_cast<int>(std::ceil((box.hi.x - box.lo.x) / a)) + 1;
    const int ny = static_cast<int>(std::ceil((box.hi.y - box.lo.y) / a)) + 1;
    const int nz = static_cast<int>(std::ceil((box.hi.z - box.lo.z) / a)) + 1;
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i)
                for (int centre = 0; centre < 2; ++centre) {
                    const double o = centre ? 0.5 : 0.0;
                    const Vec3 x = R * (box.lo + Vec3{(i + o) * a, (j + o) * a, (k + o) * a});
                    if (region.depth(x) >= margin) out.push_back(x);
                }
    if (!out.empty()) *frame = {R, box.lo, a};
    return out;
}

// TetGen's mesh of the checked boundary, refined through the callback.
RawMesh mesh_with_tetgen(const TetRegion& region, const Boundary& b) {
    tetgenio in, out, addin;
    fill_input(b, in);
    // The lattice, inserted with -i.
    Aabb bbox;
    for (const Vec3& p : b.points) bbox.extend(p);
    const double M = region.lattice_hessian > 0 ? region.lattice_hessian
                                                : region.hessian_bound(0.5 * (bbox.lo + bbox.hi), 0.5 * length(bbox.hi - bbox.lo));
    LatticeFrame frame;
    const std::vector<Vec3> lattice = lattice_points(region, b, lattice_spacing(region.tolerance, M), &frame);
    if (!lattice.empty()) {
        addin.firstnumber = 0;
        addin.numberofpoints = static_cast<int>(lattice.size());
        addin.pointlist = new REAL[3 * lattice.size()];
        for (size_t i = 0; i < lattice.size(); ++i)
            for (int k = 0; k < 3; ++k) addin.pointlist[3 * i + k] = lattice[i][k];
    }
    Refinement refinement;
    refinement.region = &region;
    const int budget = static_cast<int>(
        std::clamp(static_cast<double>(region.max_tets) / kTetsPerSteinerPoint, 1.0, static_cast<double>(INT_MAX)));
    {
        std::lock_guard<std::mutex> lock(g_tetgen_mutex);
        RefinementScope scope(&refinement);
        // TetGen takes a writable char*; -i inserts the lattice (addin).
        std::string switches = fmt::format("{}{}S{}", kSwitches, lattice.empty() ? "" : "i", budget);
        try {
            ::tetrahedralize(switches.data(), &in, &out, lattice.empty() ? nullptr : &addin);
        } catch (int code) {
            fail(region, tetgen_failure(code));
        } catch (const std::bad_alloc&) {
            fail(region, "out of memory while TetGen was meshing");
        }
    }
    if (refinement.error) std::rethrow_exception(refinement.error);
    if (!refinement.invalid.empty()) fail(region, refinement.invalid);
    const long long added = static_cast<long long>(out.numberofpoints) - static_cast<long long>(b.points.size()) -
                            static_cast<long long>(lattice.size());
    if (added >= budget)
        fail(region, fmt::format("the mesh would exceed max_tets = {} tetrahedra at the tolerance {:g} on n^2 (TetGen "
                                 "stopped at its budget of {} added points, with {} tetrahedra)",
                                 region.max_tets, region.tolerance, budget, out.numberoftetrahedra));
    if (static_cast<size_t>(out.numberoftetrahedra) > region.max_tets)
        fail(region, fmt::format("the mesh would exceed max_tets = {} tetrahedra at the tolerance {:g} on n^2 (TetGen "
                                 "made {})",
                                 region.max_tets, region.tolerance, out.numberoftetrahedra));
    if (out.numberoftetrahedra <= 0) fail(region, "TetGen made no tetrahedra");
    RawMesh r = raw_mesh(region, out);
    r.lattice = frame;
    return r;
}

// ---- bisection of what TetGen left -------------------------------------------------------------

// TetGen declines to split some of the tetrahedra the callback calls unsuitable (measured: 1 in
// 10^3 to 10^5, well shaped and 1.1 to 1.2 times the tolerance, inside and near the boundary; its
// Delaunay refinement rejects Steiner points too close to existing vertices, so that it
// terminates). Meshing again does not help (the rejections move elsewhere), and a second TetGen
// pass refining its own output (-r) failed an assertion in TetGen. Those tetrahedra are refined
// here instead, by Rivara's longest-edge propagation path (LEPP) bisection: follow the longest
// edges from the tetrahedron to a terminal edge (the longest edge of every tetrahedron around
// it), and split that edge at its midpoint together with every tetrahedron around it. The mesh
// stays conforming (every tetrahedron at the edge is split), each child lies in its parent, and
// bisecting terminal edges keeps the shapes from degenerating (each tetrahedron is split across
// its own longest edge). A midpoint of a boundary edge lies on the boundary's flat triangles, so
// the region is unchanged.
class Bisection {
public:
    explicit Bisection(RawMesh& m) : m_(m) {}

    // Splits the terminal edge of t's longest-edge path; `touched` gets every tetrahedron that
    // changed or was created (t's index survives, as t itself or its child).
    void refine(std::int32_t t, std::vector<std::int32_t>& touched) {
        Edge e = longest_edge(t);
        for (bool moved = true; moved;) {
            moved = false;
            for (std::int32_t s : ring(t, e)) {
                const Edge f = longest_edge(s);
                if (longer(f, e)) {
                    t = s;
                    e = f;
                    moved = true;
                    break;
                }
            }
        }
        bisect(t, e, touched);
    }

private:
    struct Edge {
        std::uint32_t a = 0, b = 0;  // a < b
        double length2 = 0;
    };

    // A strict total order (length, then vertex numbers), so the path cannot cycle.
    static bool longer(const Edge& x, const Edge& y) {
        if (x.length2 != y.length2) return x.length2 > y.length2;
        return std::tie(x.a, x.b) > std::tie(y.a, y.b);
    }

    Edge longest_edge(std::int32_t t) const {
        const auto& v = m_.tets[t];
        Edge best;
        bool first = true;
        for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j) {
                const Edge e{std::min(v[i], v[j]), std::max(v[i], v[j]), length2(m_.vertices[v[i]] - m_.vertices[v[j]])};
                if (first || longer(e, best)) best = e;
                first = false;
            }
        return best;
    }

    int slot(std::int32_t t, std::uint32_t vertex) const {
        const auto& v = m_.tets[t];
        return static_cast<int>(std::find(v.begin(), v.end(), vertex) - v.begin());
    }

    // The other vertex of t besides the edge and `not_this`.
    std::uint32_t fourth(std::int32_t t, const Edge& e, std::uint32_t not_this) const {
        for (auto v : m_.tets[t])
            if (v != e.a && v != e.b && v != not_this) return v;
        return not_this;
    }

    // The tetrahedra around edge e, starting with t: walk across the faces that contain e, one
    // way round until back at t (an inner edge) or at the boundary, then (a boundary edge) the
    // other way from t.
    std::vector<std::int32_t> ring(std::int32_t t, const Edge& e) const {
        std::vector<std::int32_t> r{t};
        std::uint32_t others[2];
        int k = 0;
        for (auto v : m_.tets[t])
            if (v != e.a && v != e.b) others[k++] = v;
        for (int side = 0; side < 2; ++side) {
            std::int32_t cur = t;
            std::uint32_t across = others[side];  // cross the face of cur opposite this vertex
            for (;;) {
                const std::int32_t n = m_.neighbors[cur][slot(cur, across)];
                if (n == t) return r;  // round an inner edge
                if (n < 0) break;      // at the boundary
                const std::uint32_t kept = fourth(cur, e, across);  // on the shared face
                r.push_back(n);
                across = kept;
                cur = n;
            }
        }
        return r;
    }

    void bisect(std::int32_t t, const Edge& e, std::vector<std::int32_t>& touched) {
        const std::vector<std::int32_t> r = ring(t, e);
        const auto m = static_cast<std::uint32_t>(m_.vertices.size());
        m_.vertices.push_back((m_.vertices[e.a] + m_.vertices[e.b]) * 0.5);
        const auto base = static_cast<std::int32_t>(m_.tets.size());
        // Each T of the ring becomes T_a (T with b replaced by the midpoint; it keeps T's index)
        // and T_b (T with a replaced; a new index). Replacing a vertex by a point of the segment
        // keeps the orientation (the determinant halves).
        auto child_b = [&](std::int32_t s) -> std::int32_t {
            if (s < 0) return -1;
            return base + static_cast<std::int32_t>(std::find(r.begin(), r.end(), s) - r.begin());
        };
        std::vector<std::array<std::uint32_t, 4>> old_v(r.size());
        std::vector<std::array<std::int32_t, 4>> old_n(r.size());
        for (size_t k = 0; k < r.size(); ++k) {
            old_v[k] = m_.tets[r[k]];
            old_n[k] = m_.neighbors[r[k]];
        }
        m_.tets.resize(m_.tets.size() + r.size());
        m_.neighbors.resize(m_.tets.size());
        for (size_t k = 0; k < r.size(); ++k) {
            const std::int32_t T = r[k], B = base + static_cast<std::int32_t>(k);
            const int ia = slot(T, e.a), ib = slot(T, e.b);
            auto va = old_v[k], vb = old_v[k];
            va[ib] = m;
            vb[ia] = m;
            std::array<std::int32_t, 4> na = old_n[k], nb{};
            // Across the face opposite the edge's ends: T_a and T_b meet at (m, c, d); T_a keeps
            // T's neighbour across (a, c, d), T_b takes over T's neighbour N across (b, c, d).
            na[ia] = B;
            nb[ib] = T;
            nb[ia] = old_n[k][ia];
            // Across the faces containing the edge: the like children of the ring neighbours.
            for (int i = 0; i < 4; ++i)
                if (i != ia && i != ib) nb[i] = child_b(old_n[k][i]);
            m_.tets[T] = va;
            m_.neighbors[T] = na;
            m_.tets[B] = vb;
            m_.neighbors[B] = nb;
            const std::int32_t N = old_n[k][ia];
            if (N >= 0)
                for (auto& x : m_.neighbors[N])
                    if (x == T) x = B;
            touched.push_back(T);
            touched.push_back(B);
        }
    }

    RawMesh& m_;
};

// Bisects until every tetrahedron meets the criterion; returns the number of edges bisected.
size_t bisect_to_tolerance(const TetRegion& region, RawMesh& m) {
    std::vector<std::int32_t> queue;
    auto above = [&](std::int32_t t) {
        const auto& v = m.tets[t];
        const TetError e = tet_error(region, m.vertices[v[0]], m.vertices[v[1]], m.vertices[v[2]], m.vertices[v[3]]);
        if (!e.valid()) fail(region, invalid_hessian_text(e));
        return e.error > region.tolerance;
    };
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(m.tets.size()); ++t)
        if (above(t)) queue.push_back(t);
    Bisection bisection(m);
    std::vector<std::int32_t> touched;
    size_t bisected = 0;
    while (!queue.empty()) {
        const std::int32_t t = queue.back();
        queue.pop_back();
        if (!above(t)) continue;
        if (m.tets.size() >= region.max_tets)
            fail(region, fmt::format("the mesh would exceed max_tets = {} tetrahedra at the tolerance {:g} on n^2 "
                                     "(while bisecting what TetGen left above it)",
                                     region.max_tets, region.tolerance));
        touched.clear();
        bisection.refine(t, touched);
        ++bisected;
        queue.push_back(t);
        queue.insert(queue.end(), touched.begin(), touched.end());
    }
    return bisected;
}

}  // namespace

double smallest_enclosing_ball(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Vec3* centre) {
    // The smallest enclosing ball is unique, and the points on its sphere (its support, 2 to 4 of
    // them unless all coincide) have its centre as their circumcentre within their affine hull.
    // For any candidate centre q, max_i |p_i - q| is the radius of the smallest ball about q
    // containing all four; it is minimal at the true centre, which is among the candidates.
    const Vec3 p[4] = {a, b, c, d};
    double best2 = INFINITY;
    Vec3 best = (a + b) * 0.5;
    auto consider = [&](const Vec3& q) {
        if (!is_finite(q)) return;  // the circumcentre of collinear or coplanar points
        double r2 = 0;
        for (const Vec3& x : p) r2 = std::max(r2, length2(x - q));
        if (r2 < best2) {
            best2 = r2;
            best = q;
        }
    };
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) consider((p[i] + p[j]) * 0.5);
    for (int skip = 0; skip < 4; ++skip) {
        // Circumcentre of the triangle (o, o + u, o + v) in its plane, n = u x v:
        //   o + (|u|^2 (v x n) + |v|^2 (n x u)) / (2 |n|^2).
        const Vec3& o = p[skip == 0 ? 1 : 0];
        const Vec3 u = p[skip <= 1 ? 2 : 1] - o, v = p[skip <= 2 ? 3 : 2] - o;
        const Vec3 n = cross(u, v);
        consider(o + (length2(u) * cross(v, n) + length2(v) * cross(n, u)) / (2.0 * length2(n)));
    }
    // Circumcentre of the tetrahedron, u, v, w its edges from a:
    //   a + (|u|^2 (v x w) + |v|^2 (w x u) + |w|^2 (u x v)) / (2 u . (v x w)).
    const Vec3 u = b - a, v = c - a, w = d - a;
    consider(a + (length2(u) * cross(v, w) + length2(v) * cross(w, u) + length2(w) * cross(u, v)) /
                     (2.0 * dot(u, cross(v, w))));
    *centre = best;
    return std::sqrt(best2);
}

double lattice_spacing(double tolerance, double hessian_bound) {
    if (!(hessian_bound > 0)) return 0.0;
    // 10 % inside the bound: a lattice tetrahedron exactly at it would be split wherever rounding
    // tips M r^2 / 2 over the tolerance, and the splits would break the lattice's regularity.
    return 0.9 * 4.0 * std::sqrt(2.0 * tolerance / hessian_bound) / std::sqrt(5.0);
}

TetMesh tetrahedralize(const TetRegion& region, StageReport* report) {
    StageTimer timer(report, "tetgen");
    if (t_refinement != nullptr)
        fail(region, "tetrahedralize was called from a callback of a region being meshed (TetGen is not re-entrant)");
    if (!region.n2) fail(region, "the region has no field n2");
    if (!region.hessian_bound) fail(region, "the region has no hessian_bound");
    if (!(region.tolerance > 0) || !std::isfinite(region.tolerance))
        fail(region, fmt::format("the tolerance {} is not a positive number", region.tolerance));
    if (region.max_tets == 0) fail(region, "max_tets is 0");

    RawMesh raw = mesh_with_tetgen(region, checked_boundary(region));
    const size_t made = raw.tets.size();
    const size_t bisected = bisect_to_tolerance(region, raw);
    const size_t nt = raw.tets.size();

    // Orientation, clipping and the error bound over what is kept.
    std::vector<std::int32_t> new_tet(nt, -1);
    std::vector<std::int64_t> new_vertex(raw.vertices.size(), -1);
    TetMesh mesh;
    mesh.name = region.name;
    if (region.hessian) {
        mesh.lattice = raw.lattice;
        mesh.hessian = region.hessian;
    }
    size_t kept = 0;
    for (size_t t = 0; t < nt; ++t) {
        auto& v = raw.tets[t];
        const Vec3 &a = raw.vertices[v[0]], &b = raw.vertices[v[1]], &c = raw.vertices[v[2]], &d = raw.vertices[v[3]];
        const double det = dot(b - a, cross(c - a, d - a));
        // The tracer's barycentric walk divides by this determinant: a tetrahedron flat in double
        // (TetGen's exact predicates may still see a sliver of positive volume) cannot be traced.
        if (!(det != 0)) fail(region, fmt::format("tetrahedron {} is flat in double precision", t));
        if (det < 0) {  // swapping two vertices swaps the faces opposite them
            std::swap(v[0], v[1]);
            std::swap(raw.neighbors[t][0], raw.neighbors[t][1]);
        }
        const TetError e = tet_error(region, a, b, c, d);
        if (!e.valid()) fail(region, invalid_hessian_text(e));
        // Clipping: a tetrahedron whose ball misses the reachable part of the region is dropped.
        if (region.keep && !region.keep(e.centre, e.radius)) continue;
        new_tet[t] = static_cast<std::int32_t>(kept++);
        mesh.error_bound = std::max(mesh.error_bound, e.error);
        for (auto i : v) new_vertex[i] = 0;
    }

    // The kept tetrahedra and the vertices they use, renumbered in order.
    for (size_t i = 0; i < raw.vertices.size(); ++i) {
        if (new_vertex[i] < 0) continue;
        new_vertex[i] = static_cast<std::int64_t>(mesh.vertices.size());
        const Vec3& x = raw.vertices[i];
        const double n2 = region.n2(x);
        if (!std::isfinite(n2)) fail(region, fmt::format("the field n2 is {} at {}", n2, point_text(x)));
        mesh.vertices.push_back(x);
        mesh.n2.push_back(n2);
    }
    mesh.tets.reserve(kept);
    mesh.neighbors.reserve(kept);
    for (size_t t = 0; t < nt; ++t) {
        if (new_tet[t] < 0) continue;
        std::array<std::uint32_t, 4> v{};
        std::array<std::int32_t, 4> nb{};
        for (int i = 0; i < 4; ++i) {
            v[i] = static_cast<std::uint32_t>(new_vertex[raw.tets[t][i]]);
            const std::int32_t n = raw.neighbors[t][i];
            nb[i] = n < 0 ? -1 : new_tet[static_cast<size_t>(n)];
        }
        mesh.tets.push_back(v);
        mesh.neighbors.push_back(nb);
    }

    std::string notes;
    if (bisected > 0)
        notes += fmt::format("; {} edge{} bisected after TetGen's {} tetrahedra", bisected, bisected == 1 ? "" : "s", made);
    if (kept < nt) notes += fmt::format("; {} of {} tetrahedra clipped", nt - kept, nt);
    timer.done(fmt::format("{}: {} tetrahedra, {} vertices, interpolation error <= {:.2g}{}", region.name,
                           mesh.tets.size(), mesh.vertices.size(), mesh.error_bound, notes));
    return mesh;
}

}  // namespace ltm
