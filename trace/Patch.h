#pragma once
// The object's bounding patches as exact analytic primitives: the front and back caps (a sphere
// or plane restricted to rho <= a and, for a sphere, to the branch through the vertex) and the
// rim (the cylinder rho = a between the caps' edges). Also the closed ellipsoid defects.
// Used as Embree user geometry (the analytic representation) and as the tracer's exact guard.
#include <algorithm>
#include <utility>
#include <vector>

#include "geometry/Lens.h"
#include "geometry/Surface.h"
#include "geometry/TriMesh.h"
#include "trace/Intersect.h"

namespace ltm {

struct Patch {
    enum class Kind { Cap, Rim, Closed } kind = Kind::Closed;
    Surface surface;
    int tag = -1;
    double a = 0;                // aperture radius (caps and rim)
    double z_vertex = 0;         // caps: the vertex height (selects the sphere's branch)
    double z_lo = 0, z_hi = 0;   // rim: the caps' edge heights
    Aabb bounds;
    Vec3 centre;                 // a bounding sphere (for cheap rejection of closed patches)
    double bounding_radius = 0;
    // Precomputed by finalize(): the boundary tests' limits, with a few ulps of slack, and the
    // box a segment must meet for the patch to be solved (bounds inflated by kCullMargin).
    double rho2_max = 0, z_min = 0, z_max = 0;
    double rho2_inside = 0;  // rim: (a (1 - kRimInsideMargin))^2
    Aabb cull;
    void finalize();
};

// Does the ray segment [0, tmax] meet the box? (The slab test; tmax may be +inf.)
inline bool segment_meets_box(const Vec3& o, const Vec3& d, double tmax, const Aabb& b) {
    double t0 = 0, t1 = tmax;
    for (int i = 0; i < 3; ++i) {
        if (d[i] == 0) {
            if (o[i] < b.lo[i] || o[i] > b.hi[i]) return false;
            continue;
        }
        double a = (b.lo[i] - o[i]) / d[i], c = (b.hi[i] - o[i]) / d[i];
        if (a > c) std::swap(a, c);
        t0 = std::max(t0, a);
        t1 = std::min(t1, c);
        if (t0 > t1) return false;
    }
    return true;
}

// The same test with the direction's reciprocals (reciprocals(d): inv[i] = 1 / d[i], 0 where d[i] == 0),
// for a segment tested against several boxes: two roundings per slab instead of one, which the
// culling margins (kCullMargin) absorb many times over.
inline bool segment_meets_box(const Vec3& o, const Vec3& d, const Vec3& inv, double tmax, const Aabb& b) {
    double t0 = 0, t1 = tmax;
    for (int i = 0; i < 3; ++i) {
        if (d[i] == 0) {
            if (o[i] < b.lo[i] || o[i] > b.hi[i]) return false;
            continue;
        }
        double a = (b.lo[i] - o[i]) * inv[i], c = (b.hi[i] - o[i]) * inv[i];
        if (a > c) std::swap(a, c);
        t0 = std::max(t0, a);
        t1 = std::min(t1, c);
        if (t0 > t1) return false;
    }
    return true;
}

// Whether patch_hit(p, o, d, 0, tmax) can find a root at all (conservative: see kCullMargin and
// kRimInsideMargin in TraceTolerance.h). `inv`: the direction's reciprocals.
inline Vec3 reciprocals(const Vec3& d) {
    return {d.x != 0 ? 1.0 / d.x : 0.0, d.y != 0 ? 1.0 / d.y : 0.0, d.z != 0 ? 1.0 / d.z : 0.0};
}
inline bool may_hit(const Patch& p, const Vec3& o, const Vec3& d, const Vec3& inv, double tmax) {
    if (p.kind == Patch::Kind::Rim && tmax < INFINITY) {
        // Both ends inside the cylinder by the margin: a convex set, so no crossing between.
        const auto rho2 = [&](const Vec3& x) {
            const Vec3 v = x - p.surface.origin;
            const double h = dot(v, p.surface.axis);
            return dot(v, v) - h * h;
        };
        if (rho2(o) < p.rho2_inside && rho2(o + d * tmax) < p.rho2_inside) return false;
    }
    return p.cull.empty() || segment_meets_box(o, d, inv, tmax, p.cull);
}

// Does the segment o + t d, t in [0, tmax], come within the patch's bounding sphere?
inline bool segment_near(const Patch& p, const Vec3& o, const Vec3& d, double tmax) {
    const Vec3 v = p.centre - o;
    // min(max(v.d, 0), tmax) as std::fmin / std::fmax would give it (a NaN argument yields the
    // other one), written out: those are library calls here, two per defect per segment.
    const double vd = dot(v, d);
    const double lo = vd > 0.0 ? vd : 0.0;
    const double tc = tmax < lo ? tmax : lo;
    const Vec3 w = v - d * tc;
    return dot(w, w) <= p.bounding_radius * p.bounding_radius;
}

// The front, back and rim patches of a lens, tagged 0, 1, 2 (SolidBuilder's kTagFront...).
std::vector<Patch> object_patches(const Lens& lens);

// Whether a point of the patch's full surface lies on the patch (the caps' aperture and branch,
// the rim's height; always for a closed patch), with the slack of finalize().
inline bool on_patch(const Patch& p, const Vec3& x) {
    if (p.kind == Patch::Kind::Closed) return true;
    if (p.kind == Patch::Kind::Rim) return x.z >= p.z_min && x.z <= p.z_max;
    if (x.x * x.x + x.y * x.y > p.rho2_max) return false;
    if (p.surface.kind == SurfaceKind::Sphere) {
        // The branch through the vertex: on the vertex's side of the centre's z.
        const double zc = p.surface.origin.z;
        if ((x.z - zc) * (p.z_vertex - zc) <= 0) return false;
    }
    return true;
}

// The smallest root t in (tmin, tmax) of the ray o + t d (d unit) on the patch, or +inf.
// Boundary tests (rho <= a, z in [z_lo, z_hi]) allow a few ulps so that a ray through a seam is
// caught by at least one of the two patches meeting there. Inline, with the object's spheres and
// cylinder solved inline (intersect's own cases, the same arithmetic): it runs several times on
// every segment.
inline double patch_hit(const Patch& p, const Vec3& o, const Vec3& d, double tmin, double tmax) {
    const Surface& s = p.surface;
    const Roots r = s.kind == SurfaceKind::Sphere     ? intersect_sphere(s.origin, s.radius, o, d)
                    : s.kind == SurfaceKind::Cylinder ? intersect_cylinder(s.origin, s.axis, s.radius, o, d)
                                                      : intersect(s, o, d);
    for (int i = 0; i < r.count; ++i) {
        const double t = r.t[i];
        if (!(t > tmin && t < tmax)) continue;
        if (on_patch(p, o + d * t)) return t;
    }
    return INFINITY;
}

}  // namespace ltm
