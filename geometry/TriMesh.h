#pragma once
// The plain triangle mesh every stage after geometry/ sees: double-precision vertices, indexed
// triangles, and per-face surface tags into a SurfaceTable. No CGAL type ever appears here.
#include <array>
#include <cstdint>
#include <vector>

#include "geometry/Vec3.h"

namespace ltm {

struct Aabb {
    Vec3 lo{INFINITY, INFINITY, INFINITY};
    Vec3 hi{-INFINITY, -INFINITY, -INFINITY};
    void extend(const Vec3& p) { lo = min(lo, p); hi = max(hi, p); }
    void extend(const Aabb& b) { lo = min(lo, b.lo); hi = max(hi, b.hi); }
    bool overlaps(const Aabb& o, double margin = 0) const {
        return lo.x - margin <= o.hi.x && o.lo.x - margin <= hi.x && lo.y - margin <= o.hi.y &&
               o.lo.y - margin <= hi.y && lo.z - margin <= o.hi.z && o.lo.z - margin <= hi.z;
    }
    bool empty() const { return lo.x > hi.x; }
};

struct TriMesh {
    std::vector<Vec3> vertices;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::vector<std::int32_t> tags;  // one per triangle: index into the SurfaceTable

    size_t num_vertices() const { return vertices.size(); }
    size_t num_triangles() const { return triangles.size(); }

    std::uint32_t add_vertex(const Vec3& p) {
        vertices.push_back(p);
        return static_cast<std::uint32_t>(vertices.size() - 1);
    }
    void add_triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::int32_t tag) {
        triangles.push_back({a, b, c});
        tags.push_back(tag);
    }
    // Appends another mesh (indices shifted); with `flip` its faces are reversed, which turns a
    // solid's outward boundary into the wall of a cavity.
    void append(const TriMesh& other, bool flip = false);

    // The faces whose tag satisfies `keep`, with only the vertices they use (order preserved).
    template <class Pred>
    TriMesh filtered(Pred keep) const {
        TriMesh out;
        std::vector<std::uint32_t> id(vertices.size(), UINT32_MAX);
        for (size_t f = 0; f < triangles.size(); ++f) {
            if (!keep(tags[f])) continue;
            std::array<std::uint32_t, 3> t{};
            for (int k = 0; k < 3; ++k) {
                auto& v = id[triangles[f][k]];
                if (v == UINT32_MAX) v = out.add_vertex(vertices[triangles[f][k]]);
                t[k] = v;
            }
            out.add_triangle(t[0], t[1], t[2], tags[f]);
        }
        return out;
    }

    Aabb bounds() const;
    // Signed volume by the divergence theorem: sum over faces of det(a, b, c) / 6, accumulated
    // about the bounding-box centre to keep the products small.
    double signed_volume() const;
    double area() const;
    Vec3 face_normal(size_t f) const;  // unit, by the right-hand rule on the winding
    double face_area(size_t f) const;
};

}  // namespace ltm
