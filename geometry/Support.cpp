// Supporting faces (Support.h): exact orientations through CGAL, in their own small translation
// unit (only the kernel's predicates, not the mesh processing).
#include "geometry/Support.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace ltm {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P3 = K::Point_3;

// A k-d tree of the vertices: nodes split at the median of their box's longest axis, leaves of
// at most kLeaf vertices, each node with its vertices' bounding box.
struct VertexTree {
    static constexpr int kLeaf = 16;
    struct Node {
        Aabb box;
        int begin = 0, end = 0;   // vertices order[begin, end)
        int left = -1, right = -1;
    };
    std::vector<Node> nodes;
    std::vector<std::uint32_t> order;

    explicit VertexTree(const std::vector<Vec3>& v) : order(v.size()) {
        std::iota(order.begin(), order.end(), 0u);
        if (!v.empty()) build(v, 0, static_cast<int>(v.size()));
    }
    int build(const std::vector<Vec3>& v, int begin, int end) {
        const int id = static_cast<int>(nodes.size());
        nodes.push_back({});
        Aabb box;
        for (int i = begin; i < end; ++i) box.extend(v[order[static_cast<size_t>(i)]]);
        nodes[static_cast<size_t>(id)].box = box;
        nodes[static_cast<size_t>(id)].begin = begin;
        nodes[static_cast<size_t>(id)].end = end;
        if (end - begin <= kLeaf) return id;
        const Vec3 e = box.hi - box.lo;
        const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
        const int mid = begin + (end - begin) / 2;
        std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                         [&](std::uint32_t a, std::uint32_t b) { return v[a][axis] < v[b][axis]; });
        const int l = build(v, begin, mid);
        const int r = build(v, mid, end);
        nodes[static_cast<size_t>(id)].left = l;
        nodes[static_cast<size_t>(id)].right = r;
        return id;
    }
};

// True when no vertex lies strictly on the side of the plane through a, b, c that `sign` (+1 or
// -1) names, with n the computed (b - a) x (c - a). The exact side of x is the sign of
// n* . (x - a), n* the exact cross product; |n - n*| <= 8 u |e1| |e2| (each component a
// difference of two rounded products of rounded differences), and the double evaluation of
// n . (x - a) adds at most 4 u |n| |x - a|_2: so the computed value is within
// err = 8 u (|e1| |e2| + |n|) |x - a|_2 <= 16 u (|e1| |e2| + |n|) |x - a|_inf (sqrt 3 < 2) of the exact
// one, and 32 u (...) covers it twice over. A box is skipped when the largest value of
// sign n . (x - a) over it (at its corners, computed with the same kind of rounding) is below
// -err at the box's farthest extent from a; a vertex is decided exactly (CGAL's orientation)
// only where its own computed value is within err of zero.
bool no_vertex_beyond(const VertexTree& tree, const std::vector<P3>& pts, const std::vector<Vec3>& v,
                      std::uint32_t ia, std::uint32_t ib, std::uint32_t ic, const Vec3& n, double err_per_length,
                      int sign) {
    const Vec3& a = v[ia];
    const CGAL::Orientation beyond = sign > 0 ? CGAL::POSITIVE : CGAL::NEGATIVE;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const VertexTree::Node& node = tree.nodes[static_cast<size_t>(stack[--top])];
        double most = 0;
        for (int k = 0; k < 3; ++k)
            most += std::max(sign * n[k] * (node.box.lo[k] - a[k]), sign * n[k] * (node.box.hi[k] - a[k]));
        const double span = std::max({node.box.hi.x - a.x, a.x - node.box.lo.x, node.box.hi.y - a.y,
                                      a.y - node.box.lo.y, node.box.hi.z - a.z, a.z - node.box.lo.z});
        if (most < -err_per_length * span) continue;
        if (node.left < 0) {
            for (int i = node.begin; i < node.end; ++i) {
                const std::uint32_t w = tree.order[static_cast<size_t>(i)];
                if (w == ia || w == ib || w == ic) continue;
                const Vec3 x = v[w] - a;
                const double reach = std::max({std::fabs(x.x), std::fabs(x.y), std::fabs(x.z)});
                if (sign * dot(n, x) < -err_per_length * reach) continue;
                if (CGAL::orientation(pts[ia], pts[ib], pts[ic], pts[w]) == beyond) return false;
            }
            continue;
        }
        // The depth of a median-split tree is log2(V / kLeaf) + 1: 128 entries hold any mesh.
        stack[top++] = node.right;
        stack[top++] = node.left;
    }
    return true;
}

}  // namespace

std::vector<SupportPlane> supporting_planes(const TriMesh& mesh) {
    constexpr double u = std::numeric_limits<double>::epsilon() * 0.5;
    const std::vector<Vec3>& v = mesh.vertices;
    std::vector<P3> pts;
    pts.reserve(v.size());
    for (const Vec3& p : v) pts.emplace_back(p.x, p.y, p.z);
    const VertexTree tree(v);
    Aabb box;
    for (const Vec3& p : v) box.extend(p);
    const double diag = v.empty() ? 0.0 : length(box.hi - box.lo);
    std::vector<SupportPlane> out(mesh.num_triangles());
    // Faces are independent: each range writes its own entries.
    const auto range = [&](size_t begin, size_t end) {
        for (size_t f = begin; f < end; ++f) {
            const auto& t = mesh.triangles[f];
            if (CGAL::collinear(pts[t[0]], pts[t[1]], pts[t[2]])) continue;
            const Vec3& a = v[t[0]];
            const Vec3 e1 = v[t[1]] - a, e2 = v[t[2]] - a;
            const Vec3 n = cross(e1, e2);
            const double len = length(n);
            if (!(len > 0) || !std::isfinite(len)) continue;
            // The rounding of the stored plane. e1, e2 are within u of their exact values
            // (componentwise, relative); each component of the cross product is a difference of two
            // products, within ~4 u |e1| |e2| of the exact one, so the computed n is within
            // 8 u |e1| |e2| of it and its direction, after the division, within
            // (8 kappa + 4) u, kappa = |e1| |e2| / |e1 x e2| (1 / sin of the angle at a). Over the
            // box, |x - a| <= diag, and c = n . a rounds by <= 3 u |a|_1: doubled,
            // slack = 16 u ((kappa + 1) diag + |a|_1).
            const double kappa = length(e1) * length(e2) / len;
            const double err_per_length = 32 * u * (length(e1) * length(e2) + len);
            const double slack = 16 * u * ((kappa + 1) * diag + std::fabs(a.x) + std::fabs(a.y) + std::fabs(a.z));
            // The side that must be empty: a closed outward mesh's vertices lie on the negative side
            // of an outward face's n, so that side is tried first; away from the mesh is then +n.
            for (const int sign : {1, -1}) {
                if (!no_vertex_beyond(tree, pts, v, t[0], t[1], t[2], n, err_per_length, sign)) continue;
                const Vec3 away = n * (sign / len);
                out[f] = {away, dot(away, a), slack};
                break;
            }
        }
    };
    // On the caller's task arena (`--threads N` bounds this as it bounds the render); the split
    // changes nothing in the result.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out.size(), 1024),
                      [&](const tbb::blocked_range<size_t>& r) { range(r.begin(), r.end()); });
    return out;
}

}  // namespace ltm
