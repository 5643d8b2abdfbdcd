#pragma once
// Local refinement of a tagged mesh near defects, so that thin features (a bubble 1 um under the
// surface, a 20 um groove) are not lost to the object's chord error.
#include <vector>

#include "geometry/SurfaceTable.h"
#include "geometry/TriMesh.h"

namespace ltm {

struct RefineRegion {
    Aabb box;               // faces whose bounding box meets this box are refined ...
    double tolerance = 0;   // ... until their chord error is at most this (mm)
};

// Longest-edge bisection (Rivara's LEPP algorithm): a face is split by bisecting its longest edge
// together with the neighbour across it, after first refining that neighbour if its own longest
// edge differs. The mesh stays conforming and the smallest angle is bounded below by half the
// initial one. A new vertex is projected onto its edge's analytic surface; an edge between two
// surfaces (a seam) is projected onto their intersection curve by alternating projections.
// Returns the number of bisections. Precondition: `mesh` is closed and manifold.
size_t refine_near(TriMesh& mesh, const SurfaceTable& table, const std::vector<RefineRegion>& regions);

}  // namespace ltm
