// The one translation unit with CGAL corefinement (slow to compile: keep it small).
#include "geometry/Boolean.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <fmt/format.h>
#include <map>

#include "geometry/CgalMesh.h"

namespace ltm {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using cgal::FaceTagMap;
using cgal::K;
using cgal::Mesh;
using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using VD = Mesh::Vertex_index;
using ExactPointMap = Mesh::Property_map<VD, EK::Point_3>;

// A read-write vertex point map holding exact points; writing one also stores its rounding in
// the mesh's own (double) point, so the mesh is always usable as a plain double mesh.
struct CorefPointMap {
    using value_type = EK::Point_3;
    using reference = const EK::Point_3&;
    using key_type = VD;
    using category = boost::read_write_property_map_tag;
    ExactPointMap* exact = nullptr;
    Mesh* mesh = nullptr;
    friend reference get(const CorefPointMap& m, key_type k) { return (*m.exact)[k]; }
    friend void put(const CorefPointMap& m, key_type k, const EK::Point_3& p) {
        (*m.exact)[k] = p;
        m.mesh->point(k) = K::Point_3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
    }
};

// Carries face tags through corefinement: sub-faces inherit the tag of the face they split, and
// faces copied from the tool into the output keep the tool's tag.
struct TagVisitor : PMP::Corefinement::Default_visitor<Mesh> {
    std::map<const Mesh*, FaceTagMap> tags;
    int current = -1;
    void before_subface_creations(Mesh::Face_index f, Mesh& tm) { current = tags.at(&tm)[f]; }
    void after_subface_created(Mesh::Face_index f, Mesh& tm) { tags.at(&tm)[f] = current; }
    void after_face_copy(Mesh::Face_index f_old, const Mesh& src, Mesh::Face_index f_new, Mesh& dst) {
        tags.at(&dst)[f_new] = tags.at(&src)[f_old];
    }
};

ExactPointMap exact_points(Mesh& m) {
    ExactPointMap e = m.add_property_map<VD, EK::Point_3>("v:exact").first;
    for (auto v : m.vertices()) {
        const auto& p = m.point(v);
        e[v] = EK::Point_3(p.x(), p.y(), p.z());
    }
    return e;
}

}  // namespace

TriMesh subtract(const TriMesh& host, const std::vector<TriMesh>& groups) {
    Mesh a;
    if (!cgal::to_surface_mesh(host, a)) throw BooleanError("the object mesh is not a valid manifold mesh");
    ExactPointMap ea = exact_points(a);
    CorefPointMap pa{&ea, &a};
    for (size_t g = 0; g < groups.size(); ++g) {
        Mesh b;
        if (!cgal::to_surface_mesh(groups[g], b))
            throw BooleanError(fmt::format("defect tool group {} is not a valid manifold mesh", g));
        ExactPointMap eb = exact_points(b);
        CorefPointMap pb{&eb, &b};
        TagVisitor visitor;
        visitor.tags.emplace(&a, a.property_map<Mesh::Face_index, int>("f:tag").first);
        visitor.tags.emplace(&b, b.property_map<Mesh::Face_index, int>("f:tag").first);
        bool ok = false;
        try {
            ok = PMP::corefine_and_compute_difference(
                a, b, a, CGAL::parameters::vertex_point_map(pa).visitor(visitor),
                CGAL::parameters::vertex_point_map(pb), CGAL::parameters::vertex_point_map(pa));
        } catch (const std::exception& e) {
            throw BooleanError(fmt::format("corefinement with defect tool group {} failed: {}", g, e.what()));
        }
        if (!ok)
            throw BooleanError(fmt::format("corefinement with defect tool group {} could not produce a "
                                           "closed solid (CGAL returned false)", g));
    }
    a.collect_garbage();
    return cgal::from_surface_mesh(a);
}

}  // namespace ltm
