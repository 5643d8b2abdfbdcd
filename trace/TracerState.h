#pragma once
// The tracer's per-path records, private to trace/: the hit record that a medium's propagation
// step returns (Tracer::Hit), a path's state between interfaces (Tracer::State) and the split
// estimator's pending branches (Tracer::SplitStack), the lockstep's view of a surface
// (Tracer::LaneFace), and the small steps every path takes (begin_segment, mesh_only_record,
// branch_result).
// Shared by Tracer.cpp (one path at a time) and Lockstep.cpp (a packet's paths side by side);
// nothing outside trace/ includes it.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "trace/TraceTolerance.h"
#include "trace/Tracer.h"

namespace ltm {

// One interface crossing found by propagate: the exact point, its surface, the unit normal
// pointing from the surface's `inside` medium to its `outside`, and how the ray arrived there.
struct Tracer::Hit {
    bool found = false;
    bool lost = false;      // a curved path in a closed medium found no exit
    double t = INFINITY;    // the segment's parameter: distance (straight) or tau (curved)
    double length = 0;      // arc length travelled (Beer-Lambert)
    Vec3 p, n_out;
    Vec3 d_in;              // unit direction arriving at p
    double n_from = 1;      // the current medium's index at p
    int tag = -1;
    std::uint32_t prim = 0;
    bool triangle = false;
    double offset = 0;  // how far a spawned ray must start off the surface
    int solved_patch = -1;  // an object patch already solved exactly over (0, t]
    // The segment's medium, when the tracer's belief was wrong and the geometry repaired it (see
    // Tracer::repair_medium): the path recorded this medium for the segment, not the belief.
    bool repaired = false;
    Medium medium = Medium::Air;
};

struct Tracer::State {
    Vec3 o, d;
    Medium medium = Medium::Air;
    double weight = 1;
    // The triangle just left, skipped by the next query while the ray is still within the band
    // in which facet and surface can differ.
    std::uint32_t skip_prim = 0;
    bool skip = false;
    double skip_until = 0;
    // Nothing of the object can be met again along this segment: the path left a convex object
    // through one of its own faces into the outside air (the analytic and refined
    // representations: the object's defects all lie inside it), or, mesh-only, the facet just
    // left is a supporting face of the whole mesh and the ray leaves it (mesh_clear_ahead).
    bool escaped = false;
    int defect = -1;  // PathResult::defect
    int depth = 0;           // interactions so far (max_depth, rr_depth)
    int splits_left = 0;     // Fresnel interactions this branch still splits (the split estimator)
    int random_choices = 0;  // PathResult::random_choices
};

// What the lockstep interaction (Tracer::lanes_interact) needs of a surface crossed from one
// side, read from one small record instead of the surface table and the media table: for tag and
// `entering` (the ray crosses from the surface's outside to its inside), lane_faces_[2 tag +
// entering]. Filled once by the constructor from those tables, by interact's rules.
struct Tracer::LaneFace {
    Medium to = Medium::Air;  // the medium after a transmission
    double n_to = 1;      // the index of `to` (a straight medium's constant; unused otherwise)
    int defect = -1;      // SurfaceInfo::defect
    // The SIMD step applies: an optical surface, not an absorbing rim, `to` neither the absorber
    // nor a curved medium. (Where a smooth inclusion can reach the face, `inclusions` says that
    // `to` depends on the point: lanes_interact decides it there as interact does.)
    bool simple = false;
    bool inclusions = false;
    bool escapes = false;  // a transmission here leaves a convex object (State::escaped)
};

// The branches of a split camera sample that wait to be traced, depth first. Capacity: a split
// pushes its reflected branch with one split fewer left than the branch had and the traced
// branch continues with as many, so from bottom to top the stack holds strictly decreasing
// numbers of splits left, all at least the traced branch's, all in [0, split_depth - 1]: at most
// split_depth states, whatever the tree. A fixed array: no allocation per camera sample.
struct Tracer::SplitStack {
    std::array<State, kMaxSplitDepth> items;
    int size = 0;
};

// Two small steps that both the path-at-a-time tracer (Tracer.cpp) and the lockstep one
// (Lockstep.cpp) take for every path, defined here so that each inlines them: the record is then
// written once where it lives (a returned PathResult copied into the results, or a Hit reset
// before its fields are set, would be a store reloaded and a stall; perf).

// Before every segment: the depth limit (a path that reaches it is truncated), and the segment's
// start for a recorded path.
inline bool Tracer::begin_segment(State& st, PathStats& stats, PrincipalPath* rec) const {
    const int depth = st.depth;
    if (depth >= options_.max_depth) {
        ++stats.truncated;
        stats.lost_weight += st.weight;
        if (rec) rec->truncated = true;
        st.weight = 0;
        return false;
    }
    if (rec) rec->segments.push_back({st.o, st.d, st.medium, st.skip, st.skip_prim, st.skip_until, st.escaped});
    return true;
}

// mesh_only_hit's record of a triangle hit.
inline void Tracer::mesh_only_record(const Vec3& o, const Vec3& d, const Candidate& c, Hit& h) const {
    h.found = true;
    h.t = c.t;
    h.tag = c.tag;
    h.prim = c.prim;
    h.triangle = true;
    h.p = o + d * c.t;
    h.n_out = face_normals_[c.prim];
    h.offset = mesh_only_offset(h.p, c.t);
}

// The spawn offset of a triangle hit at p, t along its ray: the float hit's error, a few float
// ulps of the coordinates involved. (The largest of the four as std::max({...}) picks it, the
// first largest by <, written out: the list's loop is a visible cost per hit; perf.)
inline double Tracer::mesh_only_offset(const Vec3& p, double t) {
    double mag = std::fabs(p.x);
    if (mag < std::fabs(p.y)) mag = std::fabs(p.y);
    if (mag < std::fabs(p.z)) mag = std::fabs(p.z);
    if (mag < std::fabs(t)) mag = std::fabs(t);
    return trace_tol::kMeshOnlyOffsetUlps * trace_tol::kFloatUlp * mag;
}

// The mesh-only escape rule: a ray spawned off a supporting face, beyond its plane and not heading
// back (clears_mesh), meets no triangle, so the query's answer is known: nothing. The test is
// made on what Embree would see, the float-rounded ray against the float vertices the planes were
// built from (the constructor), so it is exact for that query, not an approximation of it. The
// convex objects' analytic rule (LaneFace::escapes) cannot serve here: the tessellation of a
// convex object is not exactly convex (4 % of the paper lens's faces have a vertex up to 0.8 um
// beyond their plane; docs/benchmarks.md), and those faces keep their query.
inline bool Tracer::mesh_clear_ahead(const State& st) const {
    return st.skip && mesh_clear_ahead(st.skip_prim, st.o, st.d);
}
inline bool Tracer::mesh_clear_ahead(std::uint32_t prim, const Vec3& o, const Vec3& d) const {
    if (clear_planes_.empty()) return false;
    const auto f = [](double x) { return static_cast<double>(static_cast<float>(x)); };
    return clears_mesh(clear_planes_[prim], {f(o.x), f(o.y), f(o.z)}, {f(d.x), f(d.y), f(d.z)});
}

// Where an ended branch lands on the display (weight 0 or off the display: pixel -1), written
// into r, a PathResult as constructed (the caller's emplace_back: written where it stays).
inline void Tracer::branch_result(const State& st, PathStats& stats, PathResult& r) const {
    branch_result(st, stats, stats.display_weight, r);
}
inline void Tracer::branch_result(const State& st, PathStats& stats, double& display_weight, PathResult& r) const {
    ++stats.branches;
    r.defect = st.defect;
    r.random_choices = st.random_choices;
    if (st.weight == 0) return;
    if (st.d.z <= 0) {
        ++stats.toward_camera;
        return;
    }
    const double t = (display_.z - st.o.z) / st.d.z;
    const long l = t > 0 ? display_.pixel(st.o.x + t * st.d.x, st.o.y + t * st.d.y) : -1;
    if (l < 0) {
        ++stats.off_display;
        return;
    }
    ++stats.on_display;
    display_weight += st.weight;
    r.pixel = l;
    r.weight = st.weight;
}

}  // namespace ltm
