#pragma once
// From a defect model to geometry: its placement checks against the object, its analytic
// surfaces (added to the SurfaceTable) and its tool mesh for the Boolean.
#include <string>
#include <vector>

#include "defects/Defect.h"
#include "geometry/IndexField.h"
#include "geometry/Lens.h"
#include "geometry/SurfaceTable.h"
#include "geometry/TriMesh.h"

namespace ltm {

// Why a defect cannot be placed in this object. `key` is relative to the defect's own mapping
// (e.g. "radius", "center", "start"), so the scene loader can report `defects[2].center`.
struct DefectProblem {
    std::string key, message;
};
// `field` is the glass's index: an inhomogeneity needs a homogeneous glass around it, and a defect
// that cuts a face (a scratch, an open pit) needs one too (graded-index paths are traced against
// the object's exact faces and enclosed defects only, trace/GrinPath.h).
std::vector<DefectProblem> defect_problems(const Lens& lens, const Defect& d, const IndexField& field = {});

// Problems of defect `d` with an earlier defect `other` (index `other_index` in the scene): an
// inhomogeneity may overlap no other defect (its field and the other's surfaces are traced
// separately). Judged by bounding boxes, which is conservative: boxes that overlap are rejected
// even where the shapes would not touch. Keys as for defect_problems ("center").
std::vector<DefectProblem> defect_pair_problems(const Lens& lens, const Defect& d, const Defect& other,
                                                int other_index);

// An axis-aligned box containing the defect: exact for ellipsoids (the half-extent along world
// axis i is sqrt(sum_j (F_ij e_j)^2)); for a scratch, its path sampled and widened by the groove's
// reach and the sampling's chord sag.
Aabb defect_bounds(const Lens& lens, const Defect& d);

// Clearance of an ellipsoid (or sphere) from the glass boundary: the smallest gap between it and
// any face, positive when it lies strictly inside the glass, <= 0 when it touches or crosses it.
// Exact for spheres (patch distances) and for ellipsoids against planes, spheres and the rim
// (farthest / closest point of the ellipsoid by Eberly's secular equation).
double ellipsoid_clearance(const Lens& lens, const Vec3& centre, const Mat3& frame, const Vec3& semi_axes);

struct DefectSolid {
    TriMesh tool;              // closed, outward; its tags index the table
    double chord_error = 0;    // bound on the tool's face-to-surface distance, mm
    double clearance = 0;      // bubbles and particles: ellipsoid_clearance; scratches: -1
    Aabb bounds;
    std::vector<int> tags;     // the table entries this defect added
};

// Adds an ellipsoid defect's surface to `table` (named "<type> <index>": bubble, pit, particle,
// inhomogeneity) and returns its tag.
int add_defect_surfaces(const Defect& d, int index, SurfaceTable& table);

// Adds the defect's surfaces to `table` (named "<type> <index> ...") and tessellates its tool
// with chord error <= tolerance.
DefectSolid make_defect_solid(const Lens& lens, const Defect& d, int index, double tolerance, SurfaceTable& table);

// The chord tolerance for a defect's tool: min(object tolerance, relative x its smallest size).
double defect_tolerance(const Defect& d, double object_tolerance, double relative);

}  // namespace ltm
