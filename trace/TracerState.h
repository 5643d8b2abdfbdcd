#pragma once
// The tracer's per-path records, private to trace/: the hit record that a medium's propagation
// step returns (Tracer::Hit), a path's state between interfaces (Tracer::State) and the split
// estimator's pending branches (Tracer::SplitStack). Shared by Tracer.cpp (one path at a time) and
// Lockstep.cpp (a packet's paths side by side); nothing outside trace/ includes it.
#include <array>
#include <cmath>
#include <cstdint>

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
    // Left a convex object through one of its own faces into the outside air: nothing of the
    // object (whose defects all lie inside it) can be met again.
    bool escaped = false;
    int defect = -1;  // PathResult::defect
    int depth = 0;           // interactions so far (max_depth, rr_depth)
    int splits_left = 0;     // Fresnel interactions this branch still splits (the split estimator)
    int random_choices = 0;  // PathResult::random_choices
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

}  // namespace ltm
