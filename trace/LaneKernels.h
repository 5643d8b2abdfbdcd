#pragma once
// The SIMD kernels of the lockstep tracer (trace/Lockstep.cpp), behind one interface: the lane
// arrays they read and write, and a table of the kernels compiled for each instruction set.
//
// trace/LaneKernels.cpp is compiled once per instruction set, as Embree builds its kernels: for
// the x86-64 baseline (2 doubles per vector), for AVX2 (4) and for AVX-512 (8) (CMakeLists.txt,
// x86-64 only). kernels() picks the widest the processor runs, once. Every set gives the same
// bits: each lane computes what the scalar tracer computes for it (trace/Lanes.h says how;
// tests/trace_lanes.cpp compares the sets with each other and the twins with the scalar code).
#include <cstdint>
#include <vector>

#include "geometry/Surface.h"
#include "geometry/Vec3.h"
#include "trace/Patch.h"

namespace ltm::lanes {

// The rays of one packet (Tracer::kPacket). The kernels go through the first `count` of them a
// vector at a time; count is a multiple of the width (Kernels::lanes), the rays past the live
// ones copies of the first.
inline constexpr int kRays = 16;

// Whether a patch has lane twins: the object's caps (spheres or planes) and its rim.
inline bool lane_patch(const Patch& p) {
    return (p.kind == Patch::Kind::Cap &&
            (p.surface.kind == SurfaceKind::Sphere || p.surface.kind == SurfaceKind::Plane)) ||
           (p.kind == Patch::Kind::Rim && p.surface.kind == SurfaceKind::Cylinder);
}

// Lane arrays: vectors in memory, filled and read lane by lane by the tracer.
struct Vec3s {
    alignas(64) double x[kRays], y[kRays], z[kRays];
    void set(int j, const Vec3& v) {
        x[j] = v.x;
        y[j] = v.y;
        z[j] = v.z;
    }
    Vec3 get(int j) const { return {x[j], y[j], z[j]}; }
};

// What the analytic segment kernel reads of the object: its patches (each lane_patch), the
// surface-table entry of each (the surface on_surface evaluates and its normal sign), and the
// enclosed ellipsoids (Tracer::user_patches_), which it does not solve.
struct ObjectLanes {
    const Patch* patches = nullptr;
    int count = 0;
    const Surface* surfaces[4] = {};
    int normal_sign[4] = {};
    const Patch* ellipsoids = nullptr;
    int ellipsoid_count = 0;
};

// Tracer::analytic_hit for every lane, as far as SIMD twins reach: the nearest root of the
// object's patches, the enclosed ellipsoids only culled (a lane whose segment comes near one is
// the scalar's), and on_surface where the winner is a cap (a rim hit is the scalar's).
struct SegmentLanes {
    Vec3s o, d;                          // in: the rays
    alignas(64) double t[kRays];         // out: the nearest root on the object's patches (inf: none)
    alignas(64) std::int64_t which[kRays];  // ... its patch (index into ObjectLanes::patches), or -1
    Vec3s p, n_out;                      // ... the hit point, its outward normal
    alignas(64) double offset[kRays];    // ... and its spawn offset (Tracer::on_surface)
    alignas(64) std::int64_t scalar[kRays];  // set: the lane needs Tracer::analytic_hit itself
};

// Tracer::interact's arithmetic at an optical interface, in two halves around the Fresnel draw.
struct InteractLanes {
    Vec3s d_in, n_out, p;                       // in: the hit (Tracer::Hit)
    alignas(64) double offset[kRays];
    alignas(64) double n_from[kRays];           // ... the index before the interface
    alignas(64) double n_to[kRays];             // ... and after it (eta = n_from / n_to)
    alignas(64) std::int64_t entering[kRays];   // ... dot(d_in, n_out) < 0
    alignas(64) double skip_chord[kRays];       // ... the chord error the skip band allows for
    // ... each path's stream (Rng::state, Rng::inc); fresnel_lanes leaves state past the draw
    // where one was taken (not under TIR), as Rng::uniform does.
    alignas(64) std::uint64_t state[kRays], inc[kRays];
    alignas(64) double reflectance[kRays];      // fresnel_lanes: R (1 under TIR)
    alignas(64) std::int64_t tir[kRays];        // ... total internal reflection
    Vec3s reflected, refracted;                 // ... both directions, not normalized
    alignas(64) std::int64_t reflect[kRays];    // ... the reflected branch is taken: TIR, or uniform() < R
    Vec3s o, d;                                 // spawn_lanes: the new ray
    alignas(64) double skip_until[kRays];       // ... the band in which its facet is skipped
    alignas(64) std::int64_t finite[kRays];     // ... set where the new direction is finite
};

// Tracer::refined_hit's first attempt where the packet's candidate is a facet of one of the
// object's caps: no ellipsoid near the segment up to the candidate (Tracer::packet_answers), the
// cap's root within the candidate's window, the exact guard over the other patches (no cutting
// defect in the scene) finding nothing nearer, and on_surface. A lane where anything else happens
// (an ellipsoid near, a root outside the window, a guard hit, a non-finite result) is the
// scalar's.
struct RefineLanes {
    Vec3s o, d;                               // in: the rays
    Vec3s face_normal;                        // ... the candidate facet's normal
    alignas(64) double candidate_t[kRays];    // ... its distance (Embree's float)
    alignas(64) std::int64_t patch[kRays];    // ... its cap (index into ObjectLanes::patches)
    alignas(64) double chord[kRays];          // ... the chord error of its tag
    alignas(64) double t[kRays];              // out: the exact root
    Vec3s p, n_out;                           // ... the hit point, its outward normal
    alignas(64) double offset[kRays];         // ... and its spawn offset
    alignas(64) std::int64_t scalar[kRays];   // set: the lane needs Tracer::refined_hit itself
};

// The camera's samples of one pixel (TelecentricCamera::sample_packet). For each sample s: the
// stream Rng(seed, k, s), its first four uniforms (TelecentricCamera::sample's, in its order) and
// the stream after them, where the sample's path goes on drawing; then sample_from's arithmetic
// for the ray, the azimuth's cosine and sine included (cos_sin_turns, trace/SinCos.h).
struct CameraLanes {
    // in: the pixel and the camera (TelecentricCamera's members, converted as sample_from converts them)
    std::uint64_t key = 0;        // splitmix64(seed) ^ splitmix64(k + Rng::kStreamA)
    double strata = 1;            // the strata per axis: grid_, or spp_ (Latin hypercube)
    double column = 0, row = 0;   // the pixel's n and m
    double half_width = 0, half_height = 0;  // -0.5 width_, 0.5 height_
    double width = 0, height = 0, columns = 1, rows = 1;  // width_, height_, N_, M_
    double na = 0, focus_z = 0, depth = 0;   // na_, focus_z_, focus_z_ - start_z_
    alignas(64) std::uint64_t sample[kRays];  // ... s
    alignas(64) double stratum_x[kRays], stratum_y[kRays];  // ... its strata (s % grid_, s / grid_ or s, perm[s])
    // out: the streams after the four draws (Rng::from_state) and the ray.
    alignas(64) std::uint64_t state[kRays], inc[kRays];
    Vec3s origin, dir;
};

// One instruction set's kernels.
struct Kernels {
    const char* isa;  // "x86-64-v4" (AVX-512), "x86-64-v3" (AVX2), "baseline"
    int lanes;        // doubles per vector
    void (*analytic_segments)(const ObjectLanes& obj, SegmentLanes& s, int count);
    // origin_floor: kOriginFloor times the scene's scale (the tracer's omag floor).
    void (*refine_segments)(const ObjectLanes& obj, RefineLanes& r, int count, double origin_floor);
    // nf (the normal on the incident side), cos_i, fresnel, reflect and refract, and the
    // Fresnel choice drawn from each lane's stream (Tracer::interact's).
    void (*fresnel)(InteractLanes& a, int count);
    // The chosen direction normalized and the new ray spawned (Tracer::interact's spawn).
    void (*spawn)(InteractLanes& a, int count, double skip_floor);
    // TelecentricCamera::sample_packet (CameraLanes).
    void (*camera)(CameraLanes& c, int count);
    // The lanes to run for n rays: whole vectors.
    int count(int n) const { return (n + lanes - 1) / lanes * lanes; }
};

// The widest set this processor runs, chosen on first use.
const Kernels& kernels();
// Every set this processor runs, the widest first (tests compare them).
std::vector<const Kernels*> runnable_kernels();

}  // namespace ltm::lanes
