#include "trace/TetWalk.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "trace/Polynomial.h"
#include "trace/TraceTolerance.h"

namespace ltm {

namespace {

// The parabola of a tetrahedron as the root finder's path (H = 0, b = g): a GrinField with the
// tetrahedron's constant gradient.
QuadraticForm linear_form(const Vec3& g) {
    QuadraticForm q;
    q.b = g;
    return q;
}

// The first root in (0, tmax] of c0 + c1 t + c2 t^2 where the value goes from >= 0 to < 0, or inf.
double first_exit(double c0, double c1, double c2, double tmax) {
    double best = INFINITY;
    auto consider = [&](double t) {
        if (t > 0 && t <= tmax && t < best && c1 + 2.0 * c2 * t < 0) best = t;
    };
    if (c2 == 0) {
        if (c1 != 0) consider(-c0 / c1);
        return best;
    }
    const double disc = c1 * c1 - 4.0 * c2 * c0;
    if (!(disc > 0)) return best;
    const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
    consider(q / c2);
    if (q != 0) consider(c0 / q);
    return best;
}

// Whether the surface can pass through the ball (c, r). Exact distances for planes, spheres and
// cylinders; for an ellipsoid the body-frame radius sqrt(s) is 1/e_min-Lipschitz, so a ball
// with |sqrt(s(c)) - 1| e_min > r lies wholly on one side. A relative slack of 1e-9 keeps the
// test conservative under rounding.
bool may_meet(const Surface& s, const Vec3& c, double r) {
    const double slack = r * (1 + 1e-9) + 1e-12 * (length(c) + r);
    if (s.kind != SurfaceKind::Ellipsoid) return std::fabs(s.signed_distance(c)) <= slack;
    const Vec3 y = s.frame.transposed() * (c - s.origin);
    const Vec3& e = s.semi_axes;
    const double rho = std::sqrt((y.x / e.x) * (y.x / e.x) + (y.y / e.y) * (y.y / e.y) + (y.z / e.z) * (y.z / e.z));
    return std::fabs(rho - 1.0) * std::min({e.x, e.y, e.z}) <= slack;
}

}  // namespace

TetWalk::~TetWalk() = default;

Vec3 TetWalk::entering(const Vec3& r, const Vec3& p) const {
    if (!hessian_) return p;
    const Vec3 q = p + phase_(r, p, hessian_(r));
    return is_finite(q) ? q * (length(p) / length(q)) : p;
}

Vec3 TetWalk::leaving(const Vec3& r, const Vec3& p) const {
    if (!hessian_) return p;
    const Vec3 q = p - phase_(r, p, hessian_(r));
    return is_finite(q) ? q : p;
}

TetWalk::TetWalk(const TetMesh& mesh, std::vector<Patch> surfaces)
    : surfaces_(std::move(surfaces)), phase_(mesh.lattice), hessian_(mesh.hessian) {
    for (const Patch& s : surfaces_) quadrics_.push_back(Quadric::from(s.surface));
    const size_t nt = mesh.tets.size();
    // Order the tetrahedra along a Morton curve of their centroids (21 bits per axis), so that a
    // walk's next tetrahedron is usually near in memory.
    std::vector<Aabb> box(nt);
    for (size_t t = 0; t < nt; ++t)
        for (auto id : mesh.tets[t]) box[t].extend(mesh.vertices[id]);
    for (const Aabb& b : box) grid_box_.extend(b);
    auto spread = [](std::uint64_t v) {  // the bits of v at every third position
        v &= 0x1fffff;
        v = (v | v << 32) & 0x1f00000000ffffull;
        v = (v | v << 16) & 0x1f0000ff0000ffull;
        v = (v | v << 8) & 0x100f00f00f00f00full;
        v = (v | v << 4) & 0x10c30c30c30c30c3ull;
        v = (v | v << 2) & 0x1249249249249249ull;
        return v;
    };
    std::vector<std::pair<std::uint64_t, std::uint32_t>> order(nt);
    const Vec3 ext = grid_box_.hi - grid_box_.lo;
    for (size_t t = 0; t < nt; ++t) {
        const Vec3 c = (box[t].lo + box[t].hi) * 0.5;
        std::uint64_t code = 0;
        for (int k = 0; k < 3; ++k) {
            const double f = ext[k] > 0 ? (c[k] - grid_box_.lo[k]) / ext[k] : 0.0;
            code |= spread(static_cast<std::uint64_t>(std::clamp(f, 0.0, 1.0) * 0x1fffff)) << k;
        }
        order[t] = {code, static_cast<std::uint32_t>(t)};
    }
    std::sort(order.begin(), order.end());
    std::vector<std::int32_t> rank(nt);
    for (size_t i = 0; i < nt; ++i) rank[order[i].second] = static_cast<std::int32_t>(i);

    tets_.resize(nt);
    inv_height_.resize(nt);
    for (size_t i = 0; i < nt; ++i) {
        const size_t t = order[i].second;  // the mesh's index of the i-th tetrahedron
        const auto& v = mesh.tets[t];
        Tet& T = tets_[i];
        for (int f = 0; f < 4; ++f) {
            const int n = mesh.neighbors[t][static_cast<size_t>(f)];
            T.next[f] = n < 0 ? -1 : rank[static_cast<size_t>(n)];
            T.next_face[f] = 0;
            if (n >= 0)
                for (int j = 0; j < 4; ++j)
                    if (mesh.neighbors[static_cast<size_t>(n)][static_cast<size_t>(j)] == static_cast<std::int32_t>(t))
                        T.next_face[f] = static_cast<std::uint8_t>(j);
            // The face's plane from its vertices in ascending index order: the same numbers in both
            // tetrahedra; its sign chosen positive toward this tetrahedron's opposite vertex.
            std::array<std::uint32_t, 3> key{};
            for (int j = 0, k = 0; j < 4; ++j)
                if (j != f) key[static_cast<size_t>(k++)] = v[static_cast<size_t>(j)];
            std::sort(key.begin(), key.end());
            const Vec3 &a = mesh.vertices[key[0]], &b = mesh.vertices[key[1]], &c = mesh.vertices[key[2]];
            Plane P;
            P.n = cross(b - a, c - a);
            P.o = dot(P.n, a);
            const double height = dot(P.n, mesh.vertices[v[static_cast<size_t>(f)]]) - P.o;
            if (height < 0) {
                P.n = -P.n;
                P.o = -P.o;
            }
            T.plane[f] = P;
            inv_height_[i][static_cast<size_t>(f)] = 1.0 / std::fabs(height);
        }
        // n^2 = n2_0 + g . (x - v0): g solves [v1 - v0; v2 - v0; v3 - v0] g = [dn2_1, dn2_2, dn2_3].
        const Vec3 v0 = mesh.vertices[v[0]];
        const Vec3 e1 = mesh.vertices[v[1]] - v0, e2 = mesh.vertices[v[2]] - v0, e3 = mesh.vertices[v[3]] - v0;
        const double d1 = mesh.n2[v[1]] - mesh.n2[v[0]], d2 = mesh.n2[v[2]] - mesh.n2[v[0]], d3 = mesh.n2[v[3]] - mesh.n2[v[0]];
        const double det = dot(e1, cross(e2, e3));
        // Cramer's rule via the dual basis: g = (d1 (e2 x e3) + d2 (e3 x e1) + d3 (e1 x e2)) / det.
        T.g = (cross(e2, e3) * d1 + cross(e3, e1) * d2 + cross(e1, e2) * d3) / det;
        T.v0 = v0;
        T.n2_0 = mesh.n2[v[0]];
        // Surfaces: those passing within the enclosing ball (centre, radius).
        Vec3 centre;
        const double r = smallest_enclosing_ball(mesh.vertices[v[0]], mesh.vertices[v[1]], mesh.vertices[v[2]],
                                                 mesh.vertices[v[3]], &centre);
        T.surf_begin = static_cast<std::uint32_t>(tet_surfaces_.size());
        for (size_t s = 0; s < surfaces_.size(); ++s)
            if (may_meet(surfaces_[s].surface, centre, r)) tet_surfaces_.push_back(static_cast<std::uint32_t>(s));
        T.surf_count = static_cast<std::uint32_t>(tet_surfaces_.size()) - T.surf_begin;
    }
    // The location grid: about two tetrahedra per cell.
    const double vol = std::max(ext.x * ext.y * ext.z, 1e-300);
    const double h = std::cbrt(vol / std::max<double>(1.0, 0.5 * static_cast<double>(nt)));
    nx_ = std::max(1, static_cast<int>(std::ceil(ext.x / h)));
    ny_ = std::max(1, static_cast<int>(std::ceil(ext.y / h)));
    nz_ = std::max(1, static_cast<int>(std::ceil(ext.z / h)));
    cell_ = {ext.x / nx_, ext.y / ny_, ext.z / nz_};
    const size_t cells = static_cast<size_t>(nx_) * ny_ * nz_;
    std::vector<std::uint32_t> count(cells + 1, 0);
    auto cell_range = [&](const Aabb& b, int lo[3], int hi[3]) {
        for (int k = 0; k < 3; ++k) {
            const int n = k == 0 ? nx_ : (k == 1 ? ny_ : nz_);
            lo[k] = std::clamp(static_cast<int>(std::floor((b.lo[k] - grid_box_.lo[k]) / cell_[k])), 0, n - 1);
            hi[k] = std::clamp(static_cast<int>(std::floor((b.hi[k] - grid_box_.lo[k]) / cell_[k])), 0, n - 1);
        }
    };
    for (int pass = 0; pass < 2; ++pass) {
        if (pass == 1) {
            cell_begin_.assign(cells + 1, 0);
            for (size_t c = 0; c < cells; ++c) cell_begin_[c + 1] = cell_begin_[c] + count[c];
            cell_tets_.assign(cell_begin_[cells], 0);
            std::fill(count.begin(), count.end(), 0);
        }
        for (size_t i = 0; i < nt; ++i) {
            int lo[3], hi[3];
            cell_range(box[order[i].second], lo, hi);
            for (int z = lo[2]; z <= hi[2]; ++z)
                for (int y = lo[1]; y <= hi[1]; ++y)
                    for (int x = lo[0]; x <= hi[0]; ++x) {
                        const size_t c = (static_cast<size_t>(z) * ny_ + y) * nx_ + x;
                        if (pass == 1) cell_tets_[cell_begin_[c] + count[c]] = static_cast<std::uint32_t>(i);
                        ++count[c];
                    }
        }
    }
}

int TetWalk::locate(const Vec3& x) const {
    int idx[3];
    for (int k = 0; k < 3; ++k) {
        const int n = k == 0 ? nx_ : (k == 1 ? ny_ : nz_);
        const double f = (x[k] - grid_box_.lo[k]) / cell_[k];
        if (!(f >= -1e-9 * n && f <= n * (1 + 1e-9))) return -1;
        idx[k] = std::clamp(static_cast<int>(std::floor(f)), 0, n - 1);
    }
    const size_t c = (static_cast<size_t>(idx[2]) * ny_ + idx[1]) * nx_ + idx[0];
    int best = -1;
    double best_min = -INFINITY;
    for (std::uint32_t k = cell_begin_[c]; k < cell_begin_[c + 1]; ++k) {
        const Tet& T = tets_[cell_tets_[k]];
        // The smallest barycentric coordinate, as a fraction of the opposite vertex's height.
        double m = INFINITY;
        for (int i = 0; i < 4; ++i) m = std::min(m, face_value(T, i, x) * inv_height_[cell_tets_[k]][static_cast<size_t>(i)]);
        if (m > best_min) {
            best_min = m;
            best = static_cast<int>(cell_tets_[k]);
        }
    }
    return best_min >= -trace_tol::kLocateSlack ? best : -1;
}

double TetWalk::n2(int t, const Vec3& x) const {
    const Tet& T = tets_[static_cast<size_t>(t)];
    return T.n2_0 + dot(T.g, x - T.v0);
}

TetWalk::Exit TetWalk::walk(const Vec3& r_in, const Vec3& p_in, int tet, bool with_arc) const {
    Exit ex;
    Vec3 r = r_in, p = p_in;
    int entry = -1, zero_steps = 0;
    static const double gx[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
    static const double gw[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
    for (long step = 0; step < trace_tol::kWalkMaxSteps; ++step) {
        const Tet& T = tets_[static_cast<size_t>(tet)];
        const Vec3& g = T.g;
        // The exit face.
        double best = INFINITY;
        int best_face = -1;
        for (int i = 0; i < 4; ++i) {
            const Plane& f = T.plane[i];
            const double c1 = dot(f.n, p), c2 = 0.25 * dot(f.n, g);
            double t;
            if (i == entry) {
                // s = tau (c1 + c2 tau): the other root, if the path curves back out.
                t = (c2 < 0 && c1 > 0) ? -c1 / c2 : INFINITY;
            } else {
                const double c0 = dot(f.n, r) - f.o;
                if (c0 <= 0 && (c1 < 0 || (c1 == 0 && c2 < 0))) t = 0;  // on or past the plane, going out
                else t = first_exit(std::max(c0, 0.0), c1, c2, INFINITY);
            }
            if (t < best) {
                best = t;
                best_face = i;
            }
        }
        // Exact surfaces in this tetrahedron, up to the exit face.
        int hit = -1;
        if (T.surf_count > 0) {
            const GrinField field(linear_form(g), 0.0, 0.0);
            const GrinPath path(field, r, p);
            for (std::uint32_t k = T.surf_begin; k < T.surf_begin + T.surf_count; ++k) {
                const int s = static_cast<int>(tet_surfaces_[k]);
                // Up to the exit (a crossing exactly at the exit face counts: 4 u of slack).
                const double limit = best * (1 + 4 * trace_tol::kU);
                const double t = CurvedQuadric(field, quadrics_[static_cast<size_t>(s)])
                                     .first_crossing(path, 0.0, limit, &surfaces_[static_cast<size_t>(s)], 1);
                if (t < INFINITY) {
                    best = t;
                    hit = s;
                }
            }
        }
        if (!std::isfinite(best)) {  // no exit: cannot happen in a bounded tetrahedron
            ex.kind = Exit::Kind::Stuck;
            break;
        }
        if (with_arc && best > 0) {
            double s = 0;
            for (int k = 0; k < 3; ++k) s += gw[k] * length(p + g * (0.25 * best * (1 + gx[k])));
            ex.arc += 0.5 * best * s;
        }
        r = r + p * best + g * (0.25 * best * best);
        p = p + g * (0.5 * best);
        ex.tau += best;
        ex.tet = tet;
        if (hit >= 0) {
            ex.kind = Exit::Kind::Surface;
            ex.surface = hit;
            ex.r = r;
            ex.p = p;
            return ex;
        }
        ++ex.crossings;
        zero_steps = best == 0 ? zero_steps + 1 : 0;
        if (zero_steps > trace_tol::kWalkMaxZeroSteps) break;
        const int next = T.next[best_face];
        if (next < 0) {
            ex.kind = Exit::Kind::Boundary;
            ex.r = r;
            ex.p = p;
            return ex;
        }
        entry = T.next_face[best_face];
        tet = next;
    }
    ex.kind = Exit::Kind::Stuck;
    ex.r = r;
    ex.p = p;
    return ex;
}

}  // namespace ltm
