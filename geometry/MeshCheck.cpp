// Solid invariants through CGAL (a separate translation unit from Boolean.cpp so the two slow
// template instantiations compile in parallel).
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/boost/graph/helpers.h>

#include "geometry/Boolean.h"
#include "geometry/CgalMesh.h"

#include <unordered_map>

namespace ltm {

namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

// A vertex of a closed triangle mesh is manifold when the edges opposite it in its incident
// faces (its link) form exactly one cycle. O(F); CGAL's is_non_manifold_vertex is meant for
// single queries and took seconds over a whole mesh.
size_t count_non_manifold_vertices(const TriMesh& m) {
    std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> link(m.num_vertices());
    for (const auto& t : m.triangles)
        for (int k = 0; k < 3; ++k) link[t[k]].push_back({t[(k + 1) % 3], t[(k + 2) % 3]});
    size_t bad = 0;
    std::unordered_map<std::uint32_t, std::uint32_t> next;
    for (const auto& l : link) {
        if (l.empty()) continue;
        next.clear();
        bool ok = true;
        for (const auto& [a, b] : l) ok = next.emplace(a, b).second && ok;
        // Follow the cycle from the first edge; it must visit every link edge.
        size_t steps = 0;
        std::uint32_t v = l.front().first;
        do {
            auto it = next.find(v);
            if (it == next.end()) { ok = false; break; }
            v = it->second;
            ++steps;
        } while (v != l.front().first && steps <= l.size());
        if (!ok || steps != l.size()) ++bad;
    }
    return bad;
}

}  // namespace

SolidCheck check_solid(const TriMesh& mesh) {
    SolidCheck c;
    cgal::Mesh m;
    c.valid_input = cgal::to_surface_mesh(mesh, m);
    c.vertices = m.number_of_vertices();
    c.faces = m.number_of_faces();
    c.closed = CGAL::is_closed(m);
    c.non_manifold_vertices = count_non_manifold_vertices(mesh);
    auto fcc = m.add_property_map<cgal::Mesh::Face_index, std::size_t>("f:cc").first;
    c.components = PMP::connected_components(m, fcc);
    if (!c.valid_input || !c.closed) return c;
    c.self_intersecting = PMP::does_self_intersect(m);
    if (!c.self_intersecting) c.bounds_volume = PMP::does_bound_a_volume(m);
    c.volume = PMP::volume(m);
    return c;
}

}  // namespace ltm
