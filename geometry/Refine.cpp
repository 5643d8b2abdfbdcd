#include "geometry/Refine.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <unordered_map>

#include "geometry/Tessellate.h"

namespace ltm {

namespace {

struct EdgeFaces {
    int f0 = -1, f1 = -1;
};

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
    if (a > b) std::swap(a, b);
    return (std::uint64_t(a) << 32) | b;
}

class Refiner {
public:
    Refiner(TriMesh& m, const SurfaceTable& t) : m_(m), table_(t) {
        edges_.reserve(m.num_triangles() * 2);
        for (size_t f = 0; f < m.num_triangles(); ++f) link(static_cast<int>(f));
    }

    // Index (0..2) of the longest edge of face f: the edge from corner k to k+1. Ties are broken
    // by the edge's vertex ids so that both faces sharing an edge agree on it.
    int longest_edge(int f) const {
        const auto& t = m_.triangles[f];
        int best = 0;
        double bl = -1;
        std::uint64_t bk = 0;
        for (int k = 0; k < 3; ++k) {
            const double l = length2(m_.vertices[t[(k + 1) % 3]] - m_.vertices[t[k]]);
            const std::uint64_t key = edge_key(t[k], t[(k + 1) % 3]);
            if (l > bl || (l == bl && key > bk)) {
                bl = l;
                best = k;
                bk = key;
            }
        }
        return best;
    }

    int neighbour(int f, int k) const {
        const auto& t = m_.triangles[f];
        const EdgeFaces& e = edges_.at(edge_key(t[k], t[(k + 1) % 3]));
        return e.f0 == f ? e.f1 : e.f0;
    }

    // Splits face f (and what LEPP requires first).
    size_t split(int f) {
        size_t count = 0;
        std::vector<int> stack{f};
        while (!stack.empty() && count < 1000000) {
            const int t = stack.back();
            const int k = longest_edge(t);
            const int g = neighbour(t, k);
            if (g < 0) return count;  // open mesh: not expected
            const auto& tt = m_.triangles[t];
            const std::uint64_t e = edge_key(tt[k], tt[(k + 1) % 3]);
            const auto& tg = m_.triangles[g];
            const int kg = longest_edge(g);
            if (edge_key(tg[kg], tg[(kg + 1) % 3]) == e) {
                bisect(t, k, g);
                ++count;
                stack.pop_back();
            } else {
                stack.push_back(g);
            }
        }
        return count;
    }

private:
    void link(int f) {
        const auto& t = m_.triangles[f];
        for (int k = 0; k < 3; ++k) {
            EdgeFaces& e = edges_[edge_key(t[k], t[(k + 1) % 3])];
            if (e.f0 < 0) e.f0 = f; else e.f1 = f;
        }
    }
    void unlink(int f) {
        const auto& t = m_.triangles[f];
        for (int k = 0; k < 3; ++k) {
            const std::uint64_t key = edge_key(t[k], t[(k + 1) % 3]);
            EdgeFaces& e = edges_[key];
            if (e.f0 == f) e.f0 = e.f1;
            e.f1 = -1;
            if (e.f0 < 0) edges_.erase(key);
        }
    }

    Vec3 project(const Vec3& p, int tag_a, int tag_b) const {
        const Surface& a = table_[tag_a].surface;
        if (tag_a == tag_b) return a.project(p);
        const Surface& b = table_[tag_b].surface;
        Vec3 q = p;
        for (int it = 0; it < 64; ++it) {
            const Vec3 next = b.project(a.project(q));
            if (distance(next, q) <= 1e-15 * (1.0 + length(q))) return next;
            q = next;
        }
        return q;
    }

    // Bisects edge k of face t (corner k -> k+1), shared with face g.
    void bisect(int t, int k, int g) {
        const auto T = m_.triangles[t];
        const std::uint32_t a = T[k], b = T[(k + 1) % 3], c = T[(k + 2) % 3];
        const auto G = m_.triangles[g];
        int kg = 0;
        while (!(G[kg] == b && G[(kg + 1) % 3] == a)) ++kg;
        const std::uint32_t d = G[(kg + 2) % 3];
        const Vec3 mid = project((m_.vertices[a] + m_.vertices[b]) * 0.5, m_.tags[t], m_.tags[g]);
        const std::uint32_t mv = m_.add_vertex(mid);
        unlink(t);
        unlink(g);
        const int tag_t = m_.tags[t], tag_g = m_.tags[g];
        m_.triangles[t] = {a, mv, c};
        m_.triangles[g] = {b, mv, d};
        m_.add_triangle(mv, b, c, tag_t);
        const int t2 = static_cast<int>(m_.num_triangles()) - 1;
        m_.add_triangle(mv, a, d, tag_g);
        const int g2 = static_cast<int>(m_.num_triangles()) - 1;
        link(t);
        link(g);
        link(t2);
        link(g2);
    }

    TriMesh& m_;
    const SurfaceTable& table_;
    std::unordered_map<std::uint64_t, EdgeFaces> edges_;
};

Aabb face_box(const TriMesh& m, size_t f) {
    Aabb b;
    for (int k = 0; k < 3; ++k) b.extend(m.vertices[m.triangles[f][k]]);
    return b;
}

}  // namespace

size_t refine_near(TriMesh& mesh, const SurfaceTable& table, const std::vector<RefineRegion>& regions) {
    if (regions.empty()) return 0;
    Refiner r(mesh, table);
    size_t splits = 0;
    // Sweep until no face in a region is too coarse; each sweep only looks at faces that exist
    // at its start (new faces are examined by the next sweep).
    for (int sweep = 0; sweep < 64; ++sweep) {
        size_t before = splits;
        const size_t n = mesh.num_triangles();
        for (size_t f = 0; f < n; ++f) {
            const Aabb fb = face_box(mesh, f);
            double tol = INFINITY;
            for (const auto& reg : regions)
                if (fb.overlaps(reg.box)) tol = std::min(tol, reg.tolerance);
            if (std::isinf(tol)) continue;
            if (face_deviation(mesh, f, table[mesh.tags[f]].surface, 2) > tol) splits += r.split(static_cast<int>(f));
        }
        if (splits == before) break;
    }
    return splits;
}

}  // namespace ltm
