#pragma once
// Builds the object solid with its defects: the tagged triangle mesh and the surface table that
// every later stage uses. Stages and their times go into a StageReport.
#include <stdexcept>
#include <string>
#include <vector>

#include "defects/Defect.h"
#include "geometry/Lens.h"
#include "geometry/IndexField.h"
#include "geometry/StageReport.h"
#include "geometry/SurfaceTable.h"
#include "geometry/TetMesh.h"
#include "geometry/TriMesh.h"

namespace ltm {

struct MeshOptions {
    double chord_tolerance = 1e-3;            // mm: max face-to-surface distance of the object
    double defect_relative_tolerance = 0.01;  // tools: chord error <= this x their smallest size
    bool always_boolean = false;              // corefine even strictly enclosed defects
    // Largest difference between n^2 interpolated linearly over a tetrahedron and the field's n^2,
    // anywhere in a TetGen-meshed region (smooth inhomogeneities, non-quadratic index fields).
    double index_tolerance = 1e-4;
};

struct Solid {
    TriMesh mesh;              // glass boundary (outer shell, cavity walls) + particle components
    SurfaceTable surfaces;     // mesh.tags index this
    double object_chord_error = 0;  // measured, mm
    double max_defect_chord_error = 0;
    int boolean_operations = 0;
    int enclosed_defects = 0;  // appended as reversed shells without a Boolean
    std::vector<bool> corefined;           // per defect: went through the Boolean (it cuts the glass)
    std::vector<double> tag_chord_error;   // per surface-table entry: bound on its faces' chord error, mm
    bool meshed = true;        // false: built surfaces_only, `mesh` is empty
    // TetGen-meshed regions (geometry/TetMesh.h): one per smooth inhomogeneity (region_defect[i] =
    // its defect index), or one for the whole object under a linear_n field (region_defect = -1).
    std::vector<TetMesh> regions;
    std::vector<int> region_defect;
};

// A defect that makes the solid impossible in a way that only building it shows: a particle within
// the tessellation's reach of the boundary or of another defect, or Booleans that leave no glass.
// `defect` is the index of the defect to blame (the first of several that act together), `key` a
// key of its mapping ("center", "radius"; "" for the defect as a whole), as DefectProblem's.
// what() is "defects[<defect>].<key>: <message>"; scene/SceneSolid.h locates it in the scene file.
struct DefectError : std::invalid_argument {
    DefectError(int defect, std::string key, std::string message);
    // "defects[<defect>]" or "defects[<defect>].<key>".
    std::string key_path() const;
    int defect = 0;
    std::string key, message;
};

// Tags 0, 1, 2 are always the front, back and rim.
constexpr int kTagFront = 0, kTagBack = 1, kTagRim = 2;

// The analytic surfaces of the object and all defects, without any meshing (what a tracer that
// uses analytic primitives needs).
SurfaceTable object_surfaces(const Lens& lens);

// Precondition: every defect passed defect_problems() (the scene loader ensures it).
// Defect-free: no Boolean runs. Defects whose clearance from the glass boundary and from every
// other defect exceeds both tessellations' chord errors are appended as reversed shells: that is
// the exact Boolean result, computed without corefinement. The rest are subtracted with CGAL in
// groups of non-overlapping tools. Particles and uniform inhomogeneities are appended as their
// own outward components. Smooth inhomogeneities add no faces (their boundary is no interface):
// each becomes a TetGen region, meshed within options.index_tolerance, as does the whole object
// under a linear_n `field`. No TetGen runs otherwise. Throws TetGenError naming the region.
//
// With `surfaces_only`, a scene whose defects cut nothing (no scratch, no pit, every bubble,
// particle and inclusion strictly inside the glass and apart from the others) gets its surface
// table without any mesh: the analytic representation traces closed forms only (Tracer.h), and
// tessellating would be work nobody uses. A scene with a cut gets the full mesh regardless.
//
// Throws DefectError when the Booleans leave no glass (defect_problems rejects a single void that
// holds the whole object before any Boolean runs; this is the guard for what it cannot decide:
// several voids that remove the object together, an ellipsoid that holds it more tightly than
// its inscribed ball shows), and for a particle or uniform inhomogeneity that is not clear of
// everything.
Solid build_solid(const Lens& lens, const std::vector<Defect>& defects, const MeshOptions& options,
                  StageReport* report = nullptr, const IndexField& field = IndexField{}, bool surfaces_only = false);

// The TetGen region of a smooth inhomogeneity (its circumscribed ellipsoid, clipped to the glass)
// or, with defect == nullptr, of the whole object under a linear_n field (its circumscribed
// tessellation). `name` names it in errors.
TetRegion index_region(const Lens& lens, const Defect* defect, const IndexField& field, const MeshOptions& options,
                       const std::string& name);

}  // namespace ltm
