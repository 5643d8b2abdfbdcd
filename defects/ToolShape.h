#pragma once
// The exact solid a cutting defect removes (a pit's ball or ellipsoid, a scratch's swept
// profile), as a point-membership test. The tracer uses it to know where the object's own
// surface has been cut away, without consulting the mesh.
#include "defects/Defect.h"
#include "defects/ScratchPath.h"
#include "geometry/Lens.h"
#include "geometry/TriMesh.h"

namespace ltm {

class ToolShape {
public:
    ToolShape(const Lens& lens, const Defect& d);
    // Strictly inside the tool solid (up to rounding).
    bool contains(const Vec3& p) const;
    const Aabb& bounds() const { return box_; }

private:
    Defect d_;
    ScratchPath path_;
    Mat3 inv_frame_;
    Aabb box_;
    double m_ = 0;  // how far the tool reaches out of the glass (profile t >= -m)
};

}  // namespace ltm
