#pragma once
// Paths of rays of sight from the camera through the object to the display.
//
// One integrator loop (Tracer::run): the medium the ray is in (trace/Media.h) propagates it to the
// next interface by its own step (straight segments, closed-form graded-index paths, or a walk
// through tetrahedra); at the interface the shared optics decide: Fresnel reflection or
// transmission with the local indices on both sides, Snell's law, total internal reflection,
// absorption; the spawn logic moves the new ray off the surface. The boundary of a smooth
// inhomogeneity is no optical interface: it only hands the path to the other medium's step.
//
// Straight segments have three representations of the object (TracerOptions::representation):
//  - Refined: Embree proposes candidate hits on the tagged triangle mesh; each is refined in
//    double precision to the exact analytic surface its tag names (the mesh only says *which*
//    surface is next). The object's own front, back and rim patches are also intersected exactly
//    on every segment (three quadratics), so a ray can never leak through the object's faces
//    whatever the mesh does at its vertices and edges, nor be misled by the gap between facets
//    and the true surface. Leaks through defect walls (a miss inside a closed medium, or a hit
//    approached from the wrong medium) are detected and the segment is re-queried with a
//    candidate ray jittered by a few float ulps; the hit is still computed for the true ray.
//  - Analytic: no mesh; the object's three patches are solved exactly inline on every segment and
//    its enclosed ellipsoid defects are Embree user geometry intersected exactly in the callback.
//    Only for scenes whose defects neither touch a face nor each other (no Boolean).
//  - MeshOnly: the triangle hit and the facet normal, no refinement: the baseline for the
//    error-vs-time comparison (homogeneous media only).
// Curved paths always meet the exact surfaces (the object's patches, enclosed ellipsoids).
//
// Spawned rays start from the hit point moved off the surface by a bound on the point's error
// (Intersect.h, point_error_bound) along the new direction, on the side it goes to; every
// numerical constant is derived in trace/TraceTolerance.h.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "defects/SolidBuilder.h"
#include "defects/ToolShape.h"
#include "geometry/Support.h"
#include "scene/Scene.h"
#include "trace/Camera.h"
#include "trace/EmbreeScene.h"
#include "trace/Media.h"
#include "trace/Patch.h"
#include "trace/Rng.h"

namespace ltm {

enum class Representation { Refined, Analytic, MeshOnly };
const char* to_string(Representation r);

struct TracerOptions {
    Representation representation = Representation::Refined;
    bool robust = true;          // Embree's robust (watertight) traversal
    int rr_depth = 64;           // Russian roulette from this interaction on ...
    double rr_survival = 0.9;    // ... with this survival probability (weight / q keeps it unbiased)
    int max_depth = 100000;      // a hard cap; the weight of paths it stops is reported as lost
};

// Counters of what paths did; merged across threads in a fixed order.
struct PathStats {
    std::uint64_t paths = 0, segments = 0, reflections = 0, transmissions = 0, tir = 0;
    std::uint64_t absorbed_particle = 0, absorbed_rim = 0, on_display = 0, off_display = 0, toward_camera = 0;
    std::uint64_t roulette_kills = 0, truncated = 0, nan_events = 0;
    // The split estimator (scene.tracing): interactions that followed both Fresnel branches (each
    // counts once here, not as a reflection and a transmission), and the branches the camera
    // samples ended in (`paths` counts camera samples; with the sample estimator, branches = paths).
    std::uint64_t splits = 0, branches = 0;
    std::uint64_t spurious_candidates = 0, guard_hits = 0, leak_retries = 0, leaks_unresolved = 0;
    // Rays within rounding of an edge of the glass (Tracer::repair_medium): segments whose medium
    // the geometry repaired, and chords through an edge too short to resolve. The path's media
    // stay consistent; the refraction at the edge itself is lost.
    std::uint64_t seam_repairs = 0, edge_chords = 0;
    // Camera rays whose first segment came from a coherent packet (Tracer::sample_packet), and
    // those of them that queried again alone because an ellipsoid lay near the packet's answer.
    std::uint64_t packet_segments = 0, packet_fallbacks = 0;
    // Curved paths: segments traced through a graded-index medium, path evaluations of the closed
    // forms, tetrahedra crossed, paths that found no exit (lost), |p|^2 != n^2 beyond
    // TraceTolerance's bound, walks that left their region other than through an exact surface.
    std::uint64_t grin_segments = 0, grin_evaluations = 0, tet_crossings = 0, lost = 0;
    std::uint64_t hamiltonian_violations = 0, walk_boundary_exits = 0;
    double display_weight = 0, lost_weight = 0, absorbed_weight = 0;
    void merge(const PathStats& o);
    // merge(p[0]), ..., merge(p[n - 1]), in that order.
    void merge_in_order(const PathStats* p, int n);
    // The counters of p[0 .. n) added to these (the weight sums left as they are).
    void add_counters(const PathStats* p, int n);
};

// The counters are PathStats' first kCounters members, all std::uint64_t, and the three weight
// sums follow them: the counters merge as one array (vector adds, not 29 named ones: the lockstep
// tracer merges its 16 paths' counts after every packet; perf), the sums by name.
inline void PathStats::add_counters(const PathStats* p, int n) {
    constexpr std::size_t kCounters = offsetof(PathStats, display_weight) / sizeof(std::uint64_t);
    static_assert(std::is_standard_layout_v<PathStats> && std::is_trivially_copyable_v<PathStats>);
    static_assert(kCounters == 29 && offsetof(PathStats, display_weight) == kCounters * sizeof(std::uint64_t) &&
                      sizeof(PathStats) == offsetof(PathStats, display_weight) + 3 * sizeof(double),
                  "a new PathStats field: a counter goes with the others (std::uint64_t, before the weight "
                  "sums; then update kCounters here), a weight sum after them (then add it to merge_in_order and "
                  "to sample_mesh_lockstep's sums)");
    std::uint64_t sum[kCounters];
    std::memcpy(sum, this, sizeof sum);
    for (int i = 0; i < n; ++i) {
        std::uint64_t c[kCounters];
        std::memcpy(c, &p[i], sizeof c);
        for (std::size_t k = 0; k < kCounters; ++k) sum[k] += c[k];
    }
    std::memcpy(this, sum, sizeof sum);
}

inline void PathStats::merge_in_order(const PathStats* p, int n) {
    add_counters(p, n);
    // One path after another: the same sums, to the bit, as n calls of merge.
    for (int i = 0; i < n; ++i) {
        display_weight += p[i].display_weight;
        lost_weight += p[i].lost_weight;
        absorbed_weight += p[i].absorbed_weight;
    }
}

inline void PathStats::merge(const PathStats& o) { merge_in_order(&o, 1); }

// A segment's start exactly as the integrator spawned it: where the "next interface" step of
// that segment begins (a benchmark replays the step alone: bench/StageBreakdown.h).
struct SegmentStart {
    Vec3 o, d;
    Medium medium = Medium::Air;
    bool skip = false;         // the triangle just left, skipped within skip_until
    std::uint32_t skip_prim = 0;
    double skip_until = 0;
    bool escaped = false;      // nothing of the object can be met again (State::escaped)
};

struct PrincipalPath {
    std::vector<SegmentStart> segments;  // one per segment, in order (the last one escapes or ends)
    std::vector<Vec3> vertices;
    std::vector<int> tags;
    // The medium the tracer believes each segment is in: media[i] is the medium of the segment
    // ending at vertices[i], media.back() (index vertices.size()) the one the path ends in (the
    // medium of its last, outgoing ray). Only optical interfaces are vertices: a segment that
    // crosses a smooth inhomogeneity's boundary (no interface) is recorded under its first medium.
    std::vector<Medium> media;
    Vec3 direction;
    bool absorbed = false, truncated = false, nan = false, lost = false;
    bool roulette = false;  // ended by Russian roulette (sampled paths only)
    bool display_hit = false;
    double x = 0, y = 0;
    int p = -1, q = -1;
    double transmission = 1;  // product of (1 - R) at the transmitting interfaces
    int tir = 0;
};

struct PathResult {
    long pixel = -1;   // display pixel l, or -1
    double weight = 0;
    // The first defect the path met (an index into the scene's defects), or -1, whether or not
    // the path then reached the display. Meeting a defect: hitting one of its optical surfaces (a
    // bubble or particle wall, a scratch's groove, a uniform inclusion's interface) or, for a
    // smooth inhomogeneity (no surface), passing where its index differs from the glass's
    // (rho < 1 on the chord of a segment inside its region). The first one counts: a path a
    // bubble scatters carries the bubble's signal wherever it goes next.
    int defect = -1;
    // Random decisions on this branch (Fresnel choices and roulette draws; total internal
    // reflection is no decision): a branch with none is deterministic given the camera sample's
    // origin and direction, its weight an exact product of Fresnel factors.
    int random_choices = 0;
};

class Tracer {
public:
    Tracer(const Scene& scene, const Solid& solid, TracerOptions options = {});
    ~Tracer();

    // Whether the analytic representation can trace this scene (no defect cuts the glass).
    static bool analytic_supported(const Solid& solid, std::string* why);

    // The deterministic principal path: transmitted at every interface, reflected only under
    // total internal reflection.
    PrincipalPath principal_path(const Vec3& origin, const Vec3& direction) const;
    // One Monte Carlo path with Fresnel reflection or transmission chosen with probability R.
    PathResult sample_path(const Vec3& origin, const Vec3& direction, Rng& rng, PathStats& stats) const;
    // One camera sample by the scene's estimator (scene.tracing, scene/Scene.h): appends the result
    // of each branch it ended in to `out` (which it does not clear), in a fixed depth-first order
    // (transmitted branch first). Sample: one branch, exactly sample_path's. Split: up to
    // 2^split_depth branches whose weights sum, in expectation, to what one sampled path carries.
    // Every branch draws from `rng` in that order, so the results depend on the stream alone.
    void sample_paths(const Vec3& origin, const Vec3& direction, Rng& rng, PathStats& stats,
                      std::vector<PathResult>& out) const;
    // The camera samples origins[i], directions[i] (i < n <= kBatch), each with its own stream
    // rngs[i], exactly as sample_paths one after another (the same results, bit for bit, in the
    // same order; ends[i] = out.size() after sample i), with their first segments found in
    // coherent Embree packets where the representation allows (packets()): a pixel's camera rays
    // are nearly parallel and start side by side, so they share their BVH traversal. The batch's
    // camera rays are queried together, regrouped by octant into full packets
    // (EmbreeScene::intersect_coherent); the paths then go kPacket at a time.
    static constexpr int kPacket = EmbreeScene::kPacket;
    static constexpr int kBatch = 4 * kPacket;
    // The fewest live paths sample_lockstep queries in one packet; a path alone takes the
    // single query (a 16-wide packet of one ray costs more than its rtcIntersect1).
    static constexpr int kMinLockstep = 2;
    void sample_packet(int n, const Vec3* origins, const Vec3* directions, Rng* rngs, PathStats& stats,
                       std::vector<PathResult>& out, size_t* ends) const;
    // Whether sample_packet uses packets: the mesh representations, with a few enclosed
    // ellipsoids at most (each camera ray checks them: see refined_hit) and an Embree that honours
    // ray masks.
    bool packets() const { return packets_; }
    // Whether sample_packet traces whole paths side by side (sample_lockstep, trace/Lockstep.cpp),
    // not only their first segments: each segment of the live paths from one packet query (the
    // mesh representations, with packets()) or from the object's patches solved in SIMD lanes
    // (analytic), and their interactions in SIMD lanes too. With the sample estimator (a split
    // sample's branches are traced one after another), straight media only, and no absorption in
    // the glass (each path then adds to the weight sums of PathStats at most once, at its end, so
    // summing lane by lane after the packet gives the very sums, bit for bit, of the paths traced
    // one after another).
    bool lockstep() const { return lockstep_; }
    // A read-only hook for tests that judge paths independently (tests/trace_stress.cpp): one path
    // from `origin`, which the caller says lies in `medium` (the tracer does not look it up), with
    // every vertex, tag and segment medium recorded. With `rng` the interactions are chosen as in
    // sample_path (Fresnel, Russian roulette); without, as in principal_path.
    PrincipalPath recorded_path(const Vec3& origin, const Vec3& direction, Medium medium, Rng* rng,
                                PathStats& stats) const;

    // The next interface along the ray from a point in `medium` (one segment of a path).
    struct FirstHit {
        bool found = false;
        double t = INFINITY;
        int tag = -1;
    };
    FirstHit first_hit(const Vec3& origin, const Vec3& direction, Medium medium, PathStats& stats) const;
    // The same step from a recorded segment start (PrincipalPath::segments), skip state included.
    FirstHit first_hit(const SegmentStart& start, PathStats& stats) const;
    // The first segments of n <= kBatch camera rays (from the air, nothing to skip) as
    // sample_packet finds them: regrouped into packets where packets() allows.
    void first_hits(int n, const Vec3* origins, const Vec3* directions, FirstHit* out, PathStats& stats) const;

    const Scene& scene() const { return scene_; }
    const Solid& solid() const { return solid_; }
    const Display& display() const { return display_; }
    const TelecentricCamera& camera() const { return camera_; }
    const EmbreeScene& embree() const { return *embree_; }
    Representation representation() const { return options_.representation; }
    // The medium at a point (air outside the object and inside voids).
    Medium medium_at(const Vec3& p) const;

    const MediaTable& media() const { return *media_; }

private:
    struct Hit;
    struct State;
    // The next interface from the ray's state, by its medium's propagation.
    // `first`: the triangle candidate of a camera ray from a packet (EmbreeScene::
    // intersect_packet), used in place of the segment's first Embree query.
    Hit propagate(const State& st, PathStats& stats, const Candidate* first = nullptr) const;
    // Straight segments: the hit by representation, with the segment's direction, length and index.
    Hit straight_step(const State& st, const MediumInfo& m, PathStats& stats, const Candidate* first) const;
    Hit straight_hit(const State& st, PathStats& stats, const Candidate* first) const;
    Hit analytic_hit(const State& st, PathStats& stats) const;
    Hit refined_hit(const State& st, PathStats& stats, const Candidate* first) const;
    Hit mesh_only_hit(const State& st, PathStats& stats, const Candidate* first) const;
    // mesh_only_hit's record of a triangle hit c of the ray (o, d), written into a reset h.
    void mesh_only_record(const Vec3& o, const Vec3& d, const Candidate& c, Hit& h) const;
    static double mesh_only_offset(const Vec3& p, double t);  // its spawn offset (TracerState.h)
    // Mesh-only: the ray st just spawned off a supporting face meets no triangle (TracerState.h);
    // the same for a ray (o, d) spawned off face prim.
    bool mesh_clear_ahead(const State& st) const;
    bool mesh_clear_ahead(std::uint32_t prim, const Vec3& o, const Vec3& d) const;
    // Whether a packet's triangle candidate c of the ray (o, d) is what the full single-ray query
    // returns: no ellipsoid patch (which the packet does not see) can lie before it.
    bool packet_answers(const Candidate& c, const Vec3& o, const Vec3& d) const;
    // The first segments' hits of n (2 <= n <= kPacket) camera rays from one packet (packets_).
    // Ray i counts into stats[i * stride]: all into one (stride 0) or each into its own (1,
    // sample_lockstep).
    // `found`: the rays' candidates, queried already (intersect_coherent), in place of the packet.
    void packet_hits(int n, const Vec3* origins, const Vec3* directions, Hit* out, PathStats* stats, int stride,
                     const Candidate* found = nullptr) const;
    // Curved segments.
    Hit grin_hit(const State& st, const MediumInfo& m, PathStats& stats) const;
    Hit walk_hit(const State& st, const MediumInfo& m, PathStats& stats) const;
    void on_surface(Hit& h) const;  // fills in the normal and spawn offset of an exact hit at h.p
    // The pending branches of a split camera sample (defined in Tracer.cpp).
    struct SplitStack;
    // One path (one branch) from st until it ends. With `split` (sampled paths only), a Fresnel
    // interaction while st.splits_left > 0 pushes the reflected branch onto it and continues
    // with the transmitted one.
    // `first`: the first segment's hit, found already (sample_packet).
    template <bool Principal>
    void run(State& st, Rng* rng, PathStats& stats, PrincipalPath* record, SplitStack* split,
             const Hit* first = nullptr) const;
    // run's two halves, for paths traced side by side (sample_lockstep): before a segment, the
    // depth cap and the record (false: the path ended); after it, the interaction at its hit h
    // and the spawn of the next ray (false: the path ended or left; branch_result says where).
    bool begin_segment(State& st, PathStats& stats, PrincipalPath* record) const;
    template <bool Principal>
    bool interact(State& st, const Hit& h, Rng* rng, PathStats& stats, PrincipalPath* record, SplitStack* split) const;
    // The camera samples of sample_packet traced side by side, one segment of each live path at a
    // time (lockstep(); trace/Lockstep.cpp).
    // `camera`: the camera rays' triangle candidates (the mesh representations; null for analytic).
    void sample_lockstep(int n, const Vec3* origins, const Vec3* directions, Rng* rngs, PathStats& stats,
                         std::vector<PathResult>& out, size_t* ends, const Candidate* camera) const;
    // The same for mesh-only, whose paths' states stay in lane arrays from one packet query to
    // the next (trace/Lockstep.cpp).
    void sample_mesh_lockstep(int n, const Vec3* origins, const Vec3* directions, Rng* rngs, PathStats& stats,
                              std::vector<PathResult>& out, size_t* ends, const Candidate* camera) const;
    // Its two steps over the lanes ids[0 .. m): the next interface of each (analytic: the object's
    // patches in SIMD lanes, scalar propagate for the lanes they cannot decide), and the
    // interaction at it (SIMD Fresnel, Snell and spawn; scalar interact for the uncommon ones).
    // live[i] turns false where a path ends.
    void lanes_analytic_hits(int m, const int* ids, const State* st, Hit* h, PathStats* stats) const;
    // refined: the packet's candidates c[j] of the lanes ids[j], refined in SIMD lanes where they
    // are facets of the object's caps (refined_lanes_), by refined_hit otherwise.
    void lanes_refined_hits(int m, const int* ids, const State* st, const Candidate* c, Hit* h, PathStats* stats) const;
    void lanes_interact(int m, const int* ids, State* st, const Hit* h, Rng* rngs, PathStats* stats, bool* live) const;
    // Up to this many enclosed ellipsoids, the analytic representation tests them in a loop (a box
    // test each) instead of querying Embree's BVH, whose call overhead is larger (measured, not a
    // tolerance).
    static constexpr size_t kLinearScanLimit = 16;
    // sample_paths with the first segment's hit found already (or nullptr).
    void sample_paths_from(const Vec3& origin, const Vec3& direction, Rng& rng, PathStats& stats,
                           std::vector<PathResult>& out, const Hit* first) const;
    // Where an ended branch lands on the display (weight 0 or off the display: pixel -1), written
    // into a default PathResult r (TracerState.h).
    void branch_result(const State& st, PathStats& stats, PathResult& r) const;
    // The same, its display weight added to display_weight instead of stats.display_weight.
    void branch_result(const State& st, PathStats& stats, double& display_weight, PathResult& r) const;
    // The index of medium m at point x (a field's local value).
    double index_at(Medium m, const Vec3& x) const;

    const Scene& scene_;
    const Solid& solid_;
    TracerOptions options_;
    Lens lens_;
    Display display_;
    TelecentricCamera camera_;
    std::vector<Patch> object_patches_;   // the exact guard (Refined)
    std::vector<Patch> ellipsoids_;       // enclosed ellipsoid defects (bubbles, particles, inclusions)
    std::vector<int> face_inclusions_;    // smooth inhomogeneities that a face of the object clips
    std::vector<Patch> user_patches_;     // user geometry (Analytic, Refined): the ellipsoids
    std::unique_ptr<MediaTable> media_;
    // The surfaces a closed-form graded-index path can meet, as quadrics for its root finder.
    // Patches of the same surface (a ball's two hemispheres) share one quadric and one solve.
    struct CurvedSurface {
        CurvedQuadric quadric;  // as the glass's field sees it
        std::vector<Patch> patches;
    };
    std::vector<CurvedSurface> curved_surfaces_;
    // The object's bounding sphere: every path in the glass crosses its boundary before it, so its
    // first crossing bounds the search of surfaces whose crossings take no closed form.
    std::unique_ptr<CurvedQuadric> horizon_;
    bool general_surfaces_ = false;
    // Defects that cut the glass (through the Boolean), with their exact solids and the surface
    // tags bounding them: the guard classifies crossings of these along each segment.
    struct Cutter {
        ToolShape shape;
        std::vector<int> tags;
    };
    std::vector<Cutter> cutters_;
    // The exact guard: the nearest crossing of the glass boundary (object patches minus cutters,
    // cutter walls inside the lens) in (0, tmax), or t = inf.
    // `solved_patch`: an object patch already solved over (0, tmax] by the refinement.
    Hit exact_guard(const Vec3& o, const Vec3& d, double tmax, int solved_patch) const;
    // Whether the root at t of surface `tag` along o + t d lies on the glass boundary of the exact
    // Boolean solid: for an object patch, outside every cutter; for a cutter's wall, where
    // membership of that cutter changes, within the lens and outside the other cutters; and, on
    // a seam where those tests are undecided, wherever membership of the exact solid changes
    // across the root (the edge rule). Surfaces of no cutter (enclosed ellipsoids, particles)
    // always pass.
    bool on_glass_boundary(int tag, const Vec3& o, const Vec3& d, double t) const;
    double lens_slack(int tag, const Vec3& x) const;
    bool in_glass(const Vec3& p) const;  // in the lens and outside every cutter
    // A segment's medium from the geometry where the belief proved wrong (an edge crossed within
    // rounding); the definition is at its use in Tracer.cpp.
    Hit repair_medium(const State& st, Hit h, PathStats& stats) const;
    // Where o + t d leaves the object's bounding box (t > 0), or 0 if it does not meet it.
    double bounds_exit(const Vec3& o, const Vec3& d) const;
    Aabb object_bounds_;
    double guard_step(int tag, const Vec3& x, const Vec3& d, double t) const;
    std::vector<int> tag_cutter_;  // per surface tag: its cutter's index in cutters_, or -1
    TriMesh tri_mesh_;                    // the triangles Embree sees (Refined, MeshOnly)
    std::vector<Vec3> face_normals_;
    // Mesh-only: each face's supporting plane over the triangles as Embree holds them (float
    // vertices; geometry/Support.h), empty for the other representations.
    std::vector<SupportPlane> clear_planes_;
    std::unique_ptr<EmbreeScene> embree_;
    double scale_ = 1;
    bool convex_ = false;  // the object is a convex body (Lens::is_convex)
    bool packets_ = false;  // sample_packet traces first segments in packets
    bool lockstep_ = false;  // ... and whole paths side by side (lockstep())
    bool analytic_lanes_ = false;  // analytic lockstep: every object patch has SIMD twins (trace/Lanes.h)
    bool refined_lanes_ = false;   // refined lockstep refines cap facets in SIMD (no cutting defect)
    struct LaneFace;  // a surface from one side, as lanes_interact reads it (TracerState.h)
    std::vector<LaneFace> lane_faces_;  // 2 tag + entering
};

}  // namespace ltm
