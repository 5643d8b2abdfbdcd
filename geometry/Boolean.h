#pragma once
// Boolean subtraction of tool solids from the object, by CGAL corefinement. This header is free
// of CGAL: the templates live in Boolean.cpp only (they take ~45 s to compile).
#include <stdexcept>
#include <vector>

#include "geometry/TriMesh.h"

namespace ltm {

struct BooleanError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// host minus each group in turn. Every group is a closed, outward-oriented, self-intersection
// free mesh (its components must not intersect each other); successive groups may overlap
// earlier ones. Face tags are carried through: split host faces keep their tag, faces taken from a
// tool keep the tool's tag and become (reversed) walls of the cavity.
//
// Intermediate results keep exact (Epeck) vertex coordinates through an exact vertex point map
// (CGAL's corefinement_consecutive_bool_op pattern), so consecutive differences never see
// rounded intersection points; coordinates are rounded to double once, at the end.
// Throws BooleanError naming the group if CGAL reports a failure.
TriMesh subtract(const TriMesh& host, const std::vector<TriMesh>& groups);

// Topological and geometric invariants of a closed solid's boundary.
struct SolidCheck {
    bool valid_input = true;       // every face could be added to a halfedge mesh (no edge used
                                   // by more than two faces with inconsistent winding)
    bool closed = false;           // no border edges
    size_t non_manifold_vertices = 0;
    bool self_intersecting = true;
    bool bounds_volume = false;    // CGAL does_bound_a_volume: outward shells, inward cavities
    size_t components = 0;
    double volume = 0;             // signed, CGAL PMP::volume
    size_t vertices = 0, faces = 0;
    bool ok() const {
        return valid_input && closed && non_manifold_vertices == 0 && !self_intersecting && bounds_volume;
    }
};
SolidCheck check_solid(const TriMesh& mesh);

}  // namespace ltm
