#pragma once
// The one small interface to Embree 3 (Debian ships Embree 3 only; its API differs from Embree
// 4's, so nothing else includes <embree3/rtcore.h>). Holds a scene of triangles (a tagged mesh)
// and/or analytic patches (user geometry intersected exactly in double precision).
#include <cstdint>
#include <memory>
#include <vector>

#include "geometry/TriMesh.h"
#include "trace/Patch.h"

namespace ltm {

struct Candidate {
    bool hit = false;
    bool analytic = false;   // a user-geometry patch: `t` is exact (double)
    double t = INFINITY;     // triangles: Embree's float distance
    std::uint32_t prim = 0;  // triangle index in the mesh, or patch index
    int tag = -1;
};

class EmbreeScene {
public:
    // `robust` sets RTC_SCENE_FLAG_ROBUST (watertight traversal, ~10-20 % slower).
    EmbreeScene(const TriMesh* triangles, const std::vector<Patch>* patches, bool robust);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    // First hit with t in (tmin, tmax). The double ray is kept for user geometry; triangles see
    // its float rounding. Triangles in `skip` (up to 4) are ignored when their t < skip_until.
    Candidate intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, const std::uint32_t* skip = nullptr,
                        int skip_count = 0, double skip_until = 0) const;

    // Up to kPacket rays at once through rtcIntersect16 with the coherent flag, over (0, inf),
    // against the TRIANGLES only (the user patches carry another geometry mask): out[i] is what
    // intersect(o[i], d[i], 0, inf) returns whenever no patch lies before that triangle (the
    // caller checks; Tracer::refined_hit). Requires packets_supported().
    // `skip` (optional): per ray, the one triangle to ignore while its t < until, exactly as
    // intersect's skip list of one ignores it (a ray spawned off a facet). With `rare` set (the
    // caller's rays leave their facets by an offset off the facet itself, so that they seldom
    // meet them again: mesh-only), the packet is traced without the skip filter and only the rays
    // whose answer is their skipped facet within the band are traced again with it: the same
    // answers for less work (mesh-only: 2.5-3.5 % of the command; refined rays, spawned off the
    // exact surface a chord away from the facets, meet theirs often and are slower this way).
    static constexpr int kPacket = 16;
    struct PacketSkip {
        std::uint32_t prim[kPacket];
        bool on[kPacket];
        double until[kPacket];
        bool rare = false;
    };
    void intersect_packet(const Vec3* o, const Vec3* d, int n, Candidate* out, const PacketSkip* skip = nullptr) const;
    // The same for the rays lanes[0 .. n) of arrays of rays by component (the lockstep's).
    struct RayLanes {
        const double *ox, *oy, *oz, *dx, *dy, *dz;
    };
    void intersect_packet(const RayLanes& rays, const int* lanes, int n, Candidate* out,
                          const PacketSkip* skip = nullptr) const;
    // Any number of rays with nothing to skip (camera rays), out[i] the packet query's answer for
    // ray i: the single query's, as intersect_packet's is (tests/trace_packets.cpp), but for a
    // ray through an edge between two facets, which either may take depending on the rays that
    // share its packet (the grouping is fixed by the rays, so results are too). Embree's packet
    // traversal takes the rays of one octant (the signs of the direction's components) at a time,
    // and a pixel's camera rays, spread about the axis by the aperture, fall into four: a packet
    // of one pixel's 16 samples is four traversals of about four rays. Here the rays are
    // regrouped by octant first, sixteen of one octant to a packet (the remainders pooled), so
    // several packets' worth of a pixel's samples fill the lanes.
    void intersect_coherent(const Vec3* o, const Vec3* d, int n, Candidate* out) const;
    // Whether this Embree build honours ray masks (RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED),
    // without which a packet would reach the patches' single-ray callback.
    bool packets_supported() const;

    // A bare rtcIntersect1 on the same scene (no filter, no refinement): the benchmark baseline.
    // Returns the hit primitive or -1.
    long raw_intersect(const Vec3& o, const Vec3& d, float tmin) const;

private:
    // One packet query of n rays, ray(i, r) writing ray i's origin and direction as floats.
    template <class Rays>
    void packet_query(int n, Candidate* out, const PacketSkip* skip, const Rays& ray) const;
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ltm
