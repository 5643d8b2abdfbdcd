#pragma once
// Private to geometry/: conversion between TriMesh and CGAL's Surface_mesh. Included only by the
// CGAL translation units (Boolean.cpp, MeshCheck.cpp); never by a public header.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include "geometry/TriMesh.h"

namespace ltm::cgal {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
using FaceTagMap = Mesh::Property_map<Mesh::Face_index, int>;

// Returns false if a face could not be added (a non-manifold edge or inconsistent winding).
inline bool to_surface_mesh(const TriMesh& in, Mesh& out) {
    out.clear();
    out.reserve(in.num_vertices(), 3 * in.num_triangles() / 2, in.num_triangles());
    FaceTagMap tag = out.add_property_map<Mesh::Face_index, int>("f:tag", -1).first;
    std::vector<Mesh::Vertex_index> v;
    v.reserve(in.num_vertices());
    for (const auto& p : in.vertices) v.push_back(out.add_vertex(K::Point_3(p.x, p.y, p.z)));
    bool ok = true;
    for (size_t f = 0; f < in.num_triangles(); ++f) {
        const auto& t = in.triangles[f];
        const auto fi = out.add_face(v[t[0]], v[t[1]], v[t[2]]);
        if (fi == Mesh::null_face()) ok = false;
        else tag[fi] = in.tags[f];
    }
    return ok;
}

inline TriMesh from_surface_mesh(const Mesh& in) {
    TriMesh out;
    const auto tag = in.property_map<Mesh::Face_index, int>("f:tag").first;
    std::vector<std::uint32_t> id(in.num_vertices() + in.number_of_removed_vertices(), 0);
    for (auto v : in.vertices()) {
        const auto& p = in.point(v);
        id[v.idx()] = out.add_vertex({p.x(), p.y(), p.z()});
    }
    for (auto f : in.faces()) {
        std::array<std::uint32_t, 3> t{};
        int k = 0;
        for (auto v : CGAL::vertices_around_face(in.halfedge(f), in)) t[k++ % 3] = id[v.idx()];
        out.add_triangle(t[0], t[1], t[2], tag[f]);
    }
    return out;
}

}  // namespace ltm::cgal
