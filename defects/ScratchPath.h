#pragma once
// Where a scratch's cross-section sits in space. A scratch's path lies on a spherical or flat
// face; every scratch is its profile swept either
//   - around an axis through the face's centre of curvature (a straight scratch on a sphere
//     follows a great circle: the axis is normal to its plane; an arc follows a small circle
//     about the axis through its centre point), or around the face normal for an arc on a plane;
//   - or along a straight segment (a straight scratch on a flat face).
// The profile lives in (s, t): s across the groove (tangent to the face, normal to the path),
// t the depth into the glass (t < 0 is outside the glass). In the revolved case each profile
// point maps to meridian coordinates (q, h) = (q0, h0) + s (sq, sh) + t (tq, th) (q: distance
// from the axis, h: height along it), so a straight profile edge sweeps a cone, a cylinder or a
// plane, and a circular edge a torus: the groove's walls are exact analytic surfaces.
#include "defects/Defect.h"
#include "geometry/Lens.h"
#include "geometry/Surface.h"
#include "geometry/Tessellate.h"

namespace ltm {

struct ScratchPath {
    bool revolve = true;
    // Revolved: axis through `o` along unit `u`; azimuth phi measured from e0 toward e1.
    Vec3 o, u, e0, e1;
    double phi0 = 0, phi1 = 0;
    double q0 = 0, h0 = 0, sq = 0, sh = 0, tq = 0, th = 0;
    // Extruded: from p0 along unit `dir` for `length`, s along s_axis, t along t_axis.
    Vec3 p0, dir, s_axis, t_axis;
    double length = 0;

    // The 3D point of profile point p at fraction f in [0, 1] along the path.
    Vec3 place(double f, const Point2& p) const;
    // Path length along the face (mm) and the largest distance of the tool from the axis (for the
    // chord error of the azimuthal steps).
    double path_length() const;
    // The analytic surface swept by the profile segment a-b, or by the circle of centre c and
    // radius r (in profile coordinates).
    Surface line_surface(const Point2& a, const Point2& b) const;
    Surface circle_surface(const Point2& c, double r) const;
    // The flat end caps at f = 0 and f = 1.
    Surface end_surface(int which) const;
};

// Precondition: the scratch's points are on the aperture and distinct (defect_problems checks).
ScratchPath scratch_path(const Lens& lens, const Defect& d);

}  // namespace ltm
