// A pixel's camera samples traced side by side (Tracer::lockstep): one lane per sample, every
// live path's next segment found together, every interaction computed together.
//
// Rays of one pixel start side by side, nearly parallel, and stay so through the object (most of
// them are transmitted at every interface), so
//  - the mesh representations find each segment's triangle candidates in one coherent packet
//    query (EmbreeScene::intersect_packet skips each ray's own triangle as the single query
//    does; refined_hit checks the ellipsoids the packet does not see), and
//  - the analytic representation solves the object's patches for all lanes at once in SIMD
//    (trace/Lanes.h), as do the interactions of every representation: Fresnel, Snell's law and
//    the spawn of the next ray.
// Tracing them side by side changes nothing any path computes. Each lane's arithmetic is the scalar
// tracer's, operation for operation (Lanes.h says how); a lane the SIMD step does not cover (an
// ellipsoid near the segment, a rim hit, a miss inside the glass, total absorption, Russian
// roulette, anything not finite) takes the scalar step (propagate, interact) for that segment or
// interaction (sample_lockstep; mesh-only's own loop, sample_mesh_lockstep at the end of this file,
// sends such a lane off to run alone). Each path draws from its own stream (rngs[i]) in its own
// order, and counts into its own PathStats (mesh-only: the packet's counters once, each path's
// weight sums lane by lane); those are summed after the packet in sample order: their integers in
// any order, and their weight sums exactly as one path after another adds to them, since each path
// adds to each at most once (lockstep() holds only without absorption in the glass, whose
// Beer-Lambert share is added on every segment). tests/trace_packets.cpp compares every branch and
// counter with the paths traced one at a time, bit for bit; tests/trace_lanes.cpp every SIMD twin
// with its scalar function.
#include <new>

#include "trace/LaneKernels.h"
#include "trace/Optics.h"
#include "trace/TraceTolerance.h"
#include "trace/Tracer.h"
#include "trace/TracerState.h"

namespace ltm {

static_assert(lanes::kRays == Tracer::kPacket);

namespace {

// What the kernels read of the object (the tracer's own patches and surface table).
lanes::ObjectLanes object_lanes(const std::vector<Patch>& patches, const SurfaceTable& table,
                                const std::vector<Patch>& ellipsoids) {
    lanes::ObjectLanes obj;
    obj.patches = patches.data();
    obj.count = static_cast<int>(patches.size());
    for (int k = 0; k < obj.count; ++k) {
        const SurfaceInfo& s = table[patches[static_cast<size_t>(k)].tag];
        obj.surfaces[k] = &s.surface;
        obj.normal_sign[k] = s.normal_sign;
    }
    obj.ellipsoids = ellipsoids.data();
    obj.ellipsoid_count = static_cast<int>(ellipsoids.size());
    return obj;
}

// Lanes [n, count) of the kernels' arrays as copies of lane 0: finite inputs whose results
// nobody reads (the kernels go through whole vectors).
void pad(int n, int count, lanes::Vec3s& v) {
    for (int j = n; j < count; ++j) v.set(j, v.get(0));
}
template <class T, size_t N>
void pad(int n, int count, T (&a)[N]) {
    for (int j = n; j < count; ++j) a[j] = a[0];
}
template <class... Arrays>
void pad_lanes(int n, int count, Arrays&... arrays) {
    (pad(n, count, arrays), ...);
}

}  // namespace

void Tracer::lanes_analytic_hits(int m, const int* ids, const State* st, Hit* h, PathStats* stats) const {
    const lanes::ObjectLanes obj = object_lanes(object_patches_, solid_.surfaces, user_patches_);
    const lanes::Kernels& kernels = lanes::kernels();
    lanes::SegmentLanes s;
    const int count = kernels.count(m);
    for (int j = 0; j < count; ++j) {  // lanes past m repeat the first: finite, ignored
        const State& a = st[ids[j < m ? j : 0]];
        s.o.set(j, a.o);
        s.d.set(j, a.d);
    }
    kernels.analytic_segments(obj, s, count);
    for (int j = 0; j < m; ++j) {
        const int i = ids[j];
        // A miss inside the glass is a leak for repair_medium to judge; the rest of the scalar's.
        if (s.scalar[j] || (s.which[j] < 0 && st[i].medium != Medium::Air)) {
            h[i] = propagate(st[i], stats[i]);
            continue;
        }
        // straight_step's record of analytic_hit's answer.
        Hit& r = h[i];
        r = Hit{};
        if (s.which[j] >= 0) {
            r.found = true;
            r.t = s.t[j];
            r.tag = object_patches_[static_cast<size_t>(s.which[j])].tag;
            r.p = s.p.get(j);
            r.n_out = s.n_out.get(j);
            r.offset = s.offset[j];
        }
        r.d_in = st[i].d;
        r.length = r.t;
        r.n_from = (*media_)[st[i].medium].index;
    }
}

void Tracer::lanes_refined_hits(int m, const int* ids, const State* st, const Candidate* c, Hit* h,
                                PathStats* stats) const {
    // The lanes whose packet candidate is a facet of a cap (the kernel checks that it is the single
    // query's answer, packet_answers) and the lanes in the air whose packet found nothing; the rest
    // take refined_hit with their candidate as it is.
    const lanes::ObjectLanes obj = object_lanes(object_patches_, solid_.surfaces, user_patches_);
    const lanes::Kernels& kernels = lanes::kernels();
    lanes::RefineLanes r;
    int lane_of[lanes::kRays];
    int n = 0;
    lanes::SegmentLanes miss;
    int miss_of[lanes::kRays];
    int misses = 0;
    const bool straight_air = (*media_)[Medium::Air].propagation == Propagation::Straight;
    for (int j = 0; j < m; ++j) {
        const int i = ids[j];
        const Candidate& cj = c[j];
        if (!cj.hit && st[i].medium == Medium::Air && straight_air) {
            miss_of[misses] = j;
            miss.o.set(misses, st[i].o);
            miss.d.set(misses, st[i].d);
            ++misses;
            continue;
        }
        if (!(cj.hit && !cj.analytic && cj.tag >= 0 && cj.tag < static_cast<int>(object_patches_.size()) &&
              object_patches_[static_cast<size_t>(cj.tag)].kind == Patch::Kind::Cap)) {
            h[i] = propagate(st[i], stats[i], &cj);
            continue;
        }
        lane_of[n] = j;
        r.o.set(n, st[i].o);
        r.d.set(n, st[i].d);
        r.face_normal.set(n, face_normals_[cj.prim]);
        r.candidate_t[n] = cj.t;
        r.patch[n] = cj.tag;
        r.chord[n] = solid_.tag_chord_error[static_cast<size_t>(cj.tag)];
        ++n;
    }
    if (misses > 0) {
        // A ray in the air past every facet (a camera ray beside the lens, a ray reflected away):
        // refined_hit takes the packet's answer where no ellipsoid lies near the ray
        // (packet_answers over the whole ray), and then finds nothing where the exact guard, the
        // object's patches solved over the whole ray, finds no root either. The analytic segment
        // kernel computes both: the nearest root over the object's patches (exact_guard's loop
        // with tmax = inf is analytic_hit's) and, where there is none, the ellipsoids' test over
        // the whole ray (packet_answers'). Any other outcome is refined_hit's to judge.
        const int count = kernels.count(misses);
        pad_lanes(misses, count, miss.o, miss.d);
        kernels.analytic_segments(obj, miss, count);
        for (int k = 0; k < misses; ++k) {
            const int j = miss_of[k];
            const int i = ids[j];
            if (miss.scalar[k] || miss.which[k] >= 0) {
                h[i] = propagate(st[i], stats[i], &c[j]);
                continue;
            }
            ++stats[i].packet_segments;
            // straight_step's record of refined_hit's answer: nothing ahead.
            Hit& hh = h[i];
            hh = Hit{};
            hh.d_in = st[i].d;
            hh.length = hh.t;
            hh.n_from = (*media_)[st[i].medium].index;
        }
    }
    if (n == 0) return;
    const int count = kernels.count(n);
    pad_lanes(n, count, r.o, r.d, r.face_normal, r.candidate_t, r.patch, r.chord);
    kernels.refine_segments(obj, r, count, trace_tol::kOriginFloor * scale_);
    for (int k = 0; k < n; ++k) {
        const int j = lane_of[k];
        const int i = ids[j];
        const Candidate& cj = c[j];
        const SurfaceInfo& sf = solid_.surfaces[cj.tag];
        // refined_hit's check of the medium it is approached from; a wrong one retries there.
        const Vec3 n_out = r.n_out.get(k);
        const Medium from = dot(st[i].d, n_out) < 0 ? sf.outside : sf.inside;
        if (r.scalar[k] || from != st[i].medium) {
            h[i] = propagate(st[i], stats[i], &cj);
            continue;
        }
        ++stats[i].packet_segments;
        // straight_step's record of refined_hit's answer.
        Hit& hh = h[i];
        hh = Hit{};
        hh.found = true;
        hh.t = r.t[k];
        hh.tag = cj.tag;
        hh.prim = cj.prim;
        hh.triangle = true;
        hh.solved_patch = cj.tag;
        hh.p = r.p.get(k);
        hh.n_out = n_out;
        hh.offset = r.offset[k];
        hh.d_in = st[i].d;
        hh.length = hh.t;
        hh.n_from = (*media_)[st[i].medium].index;
    }
}

void Tracer::lanes_interact(int m, const int* ids, State* st, const Hit* h, Rng* rngs, PathStats* stats,
                            bool* live) const {
    // Lanes the SIMD halves take: an optical interface between straight media, a finite hit, no
    // roulette yet, packed into the kernels' lanes as they are found. The rest interact alone,
    // before anything of theirs changes here.
    lanes::InteractLanes a;
    int lane_of[lanes::kRays];  // lanes of the kernels: ids[k] for k = lane_of[j]
    Medium to[lanes::kRays];
    const LaneFace* face[lanes::kRays];
    int n = 0;
    for (int j = 0; j < m; ++j) {
        const int i = ids[j];
        const Hit& hh = h[i];
        const State& s = st[i];
        // Not short-circuited: every test is cheap, a branch for each is not.
        bool simple = hh.found & !hh.repaired & !hh.lost & (s.depth + 1 < options_.rr_depth);
        simple = simple && (is_finite(hh.p) & is_finite(hh.n_out) & is_finite(hh.d_in) & std::isfinite(hh.n_from));
        if (simple) {
            const bool in = dot(hh.d_in, hh.n_out) < 0;
            const LaneFace& f = lane_faces_[2 * static_cast<size_t>(hh.tag) + in];
            Medium t = f.to;
            double n_to = f.n_to;
            simple = f.simple;
            if (f.inclusions) {  // as interact: a face where an inclusion reaches it
                for (int k : face_inclusions_)
                    if (scene_.defects[static_cast<size_t>(k)].segment_min_rho2(hh.p, hh.p) < 1.0) t = Medium::inclusion(k);
                const MediumInfo& into = (*media_)[t];
                simple = simple && into.propagation == Propagation::Straight;
                n_to = into.index;
            }
            if (simple) {
                a.d_in.set(n, hh.d_in);
                a.n_out.set(n, hh.n_out);
                a.p.set(n, hh.p);
                a.offset[n] = hh.offset;
                a.n_from[n] = hh.n_from;
                a.n_to[n] = n_to;  // index_at of a straight medium
                a.entering[n] = in ? -1 : 0;
                a.skip_chord[n] = hh.triangle ? solid_.tag_chord_error[static_cast<size_t>(hh.tag)] : 0.0;
                a.state[n] = rngs[i].state();
                a.inc[n] = rngs[i].inc();
                to[n] = t;
                face[n] = &f;
                lane_of[n++] = j;
                continue;
            }
        }
        live[i] = interact<false>(st[i], hh, &rngs[i], stats[i], nullptr, nullptr);
    }
    if (n == 0) return;

    const lanes::Kernels& kernels = lanes::kernels();
    const int count = kernels.count(n);
    pad_lanes(n, count, a.d_in, a.n_out, a.p, a.offset, a.n_from, a.n_to, a.entering, a.skip_chord, a.state, a.inc);
    // Fresnel, and the choice drawn from each path's own stream as interact draws it.
    kernels.fresnel(a, count);
    for (int j = 0; j < n; ++j) {
        const int i = ids[lane_of[j]];
        if (a.tir[j]) {
            ++stats[i].tir;
        } else {
            rngs[i] = Rng::from_state(a.state[j], a.inc[j]);
            ++st[i].random_choices;
        }
    }
    kernels.spawn(a, count, trace_tol::kSkipFloatUlps * trace_tol::kFloatUlp * scale_);
    for (int j = 0; j < n; ++j) {
        const int i = ids[lane_of[j]];
        const Hit& hh = h[i];
        State& s = st[i];
        PathStats& ps = stats[i];
        const LaneFace& f = *face[j];
        ++ps.segments;
        if (s.defect < 0) {  // as interact
            const int k = s.medium.defect();
            if (k >= 0 && scene_.defects[static_cast<size_t>(k)].segment_min_rho2(s.o, hh.p) < 1.0) s.defect = k;
            else if (f.defect >= 0) s.defect = f.defect;
        }
        if (a.reflect[j]) {
            if (!a.tir[j]) ++ps.reflections;
        } else {
            // As interact: the face's rule alone (an inclusion only replaces the glass as `to`,
            // so it never turns an escape into the air into something else).
            s.escaped = f.escapes;
            s.medium = to[j];
            ++ps.transmissions;
        }
        if (!a.finite[j]) {  // spawn's check
            ++ps.nan_events;
            s.weight = 0;
            live[i] = false;
            continue;
        }
        s.o = a.o.get(j);
        s.d = a.d.get(j);
        s.skip = hh.triangle;
        s.skip_prim = hh.prim;
        if (hh.triangle) s.skip_until = a.skip_until[j];
        live[i] = true;
    }
}

void Tracer::sample_lockstep(int n, const Vec3* origins, const Vec3* directions, Rng* rngs, PathStats& stats,
                             std::vector<PathResult>& out, size_t* ends, const Candidate* camera) const {
    const bool analytic = options_.representation == Representation::Analytic;
    State st[kPacket];
    PathStats lane[kPacket];
    Hit h[kPacket];
    bool live[kPacket];
    int ids[kPacket];
    for (int i = 0; i < n; ++i) {
        st[i].o = origins[i];
        st[i].d = directions[i];
        st[i].medium = Medium::Air;
        ids[i] = i;
    }
    // The camera segments' hits (whatever begin_segment then says, as the paths one at a time).
    if (!analytic && !refined_lanes_)
        packet_hits(n, origins, directions, h, lane, 1, camera);
    int m = 0;
    for (int i = 0; i < n; ++i) {
        ++lane[i].paths;
        live[i] = begin_segment(st[i], lane[i], nullptr);
        if (live[i]) ids[m++] = i;
    }
    if (analytic && m > 0) lanes_analytic_hits(m, ids, st, h, lane);
    if (refined_lanes_ && m > 0) {  // the camera rays' candidates (nothing to skip), refined in lanes
        Candidate c[kPacket];
        for (int j = 0; j < m; ++j) c[j] = camera[ids[j]];
        lanes_refined_hits(m, ids, st, c, h, lane);
    }
    while (m > 0) {
        lanes_interact(m, ids, st, h, rngs, lane, live);
        // The next segment of every path still live: out of a convex object nothing is queried.
        int q = 0, next = 0;
        int query[kPacket];
        for (int j = 0; j < m; ++j) {
            const int i = ids[j];
            if (!live[i]) continue;
            ++st[i].depth;
            if (!begin_segment(st[i], lane[i], nullptr)) {
                live[i] = false;
                continue;
            }
            if (st[i].escaped && (*media_)[st[i].medium].propagation == Propagation::Straight) {
                // Out of a convex object: straight_hit finds nothing, and interact counts the
                // segment and ends the path (branch_result looks for the display), as here.
                ++lane[i].segments;
                live[i] = false;
                continue;
            }
            ids[next++] = i;
            if (st[i].escaped)
                h[i] = propagate(st[i], lane[i]);
            else
                query[q++] = i;
        }
        m = next;
        if (q == 0) continue;
        if (q < kMinLockstep) {
            for (int j = 0; j < q; ++j) h[query[j]] = propagate(st[query[j]], lane[query[j]]);
        } else if (analytic) {
            lanes_analytic_hits(q, query, st, h, lane);
        } else {
            Vec3 o[kPacket], d[kPacket];
            EmbreeScene::PacketSkip skip;
            Candidate c[kPacket];
            for (int j = 0; j < q; ++j) {
                const State& s = st[query[j]];
                o[j] = s.o;
                d[j] = s.d;
                skip.prim[j] = s.skip_prim;
                skip.on[j] = s.skip;
                skip.until[j] = s.skip_until;
            }
            embree_->intersect_packet(o, d, q, c, &skip);
            if (refined_lanes_)
                lanes_refined_hits(q, query, st, c, h, lane);
            else
                for (int j = 0; j < q; ++j) h[query[j]] = propagate(st[query[j]], lane[query[j]], &c[j]);
        }
    }
    for (int i = 0; i < n; ++i) {
        branch_result(st[i], lane[i], out.emplace_back());
        ends[i] = out.size();
    }
    stats.merge_in_order(lane, n);
}

// The mesh-only lockstep (sample_mesh_lockstep): the paths' states kept lane by lane in the
// interaction kernels' own arrays from one packet query to the next (the kernels read each ray
// where spawn_lanes left it, and each stream where fresnel_lanes left it), each hit's record made
// where they read it: no Tracer::Hit or Tracer::State per lane, nothing copied between stages
// but the hit (perf: writing and reading such records per lane would be most of the mesh-only
// lockstep's own time). Lane i is path i throughout; the kernels go through every lane, the ended ones
// included (what they compute there is never read, as for the padding lanes). A lane whose step
// the kernels do not cover leaves the lockstep for good: its state becomes a State and the path
// runs on alone (run), which is what it computes in the lockstep too (tests/trace_packets.cpp).
void Tracer::sample_mesh_lockstep(int n, const Vec3* origins, const Vec3* directions, Rng* rngs, PathStats& stats,
                                  std::vector<PathResult>& out, size_t* ends, const Candidate* camera) const {
    // Path i: its ray a.o, a.d (spawn_lanes' output, where the next segment starts), its stream
    // a.state, a.inc, and the rest of its State here.
    lanes::InteractLanes a;
    alignas(64) double weight[kPacket];
    std::uint32_t skip_prim[kPacket];
    bool skip[kPacket];
    Medium medium[kPacket];
    int depth[kPacket], defect[kPacket], choices[kPacket];
    // The packet's counts, and each path's additions to the weight sums, which are summed in
    // sample order after the packet, as one path after another adds to them (each adds to each
    // at most once: lockstep()).
    PathStats counts;
    double display_w[kPacket] = {}, lost_w[kPacket] = {};
    // The lanes that left the lockstep, with their states and their own counts (constructed as
    // they leave).
    bool alone[kPacket];
    alignas(State) unsigned char alone_storage[kPacket * sizeof(State)];
    State* const alone_st = reinterpret_cast<State*>(alone_storage);
    alignas(PathStats) unsigned char alone_counts[kPacket * sizeof(PathStats)];
    PathStats* const alone_stats = reinterpret_cast<PathStats*>(alone_counts);
    const lanes::Kernels& kernels = lanes::kernels();
    const int count = kernels.count(n);
    for (int i = 0; i < count; ++i) {  // lanes past n repeat the first: finite, ignored
        const int from = i < n ? i : 0;
        a.o.set(i, origins[from]);
        a.d.set(i, directions[from]);
        a.skip_until[i] = 0;
        a.state[i] = rngs[from].state();
        a.inc[i] = rngs[from].inc();
        a.offset[i] = a.n_from[i] = a.n_to[i] = 1;
        a.entering[i] = 0;
        a.skip_chord[i] = 0;  // mesh-only: the facets are the surface
        a.n_out.set(i, {0, 0, 1});
        a.p.set(i, origins[from]);
    }
    for (int i = 0; i < n; ++i) {
        weight[i] = 1;
        skip_prim[i] = 0;
        skip[i] = false;
        medium[i] = Medium::Air;
        depth[i] = 0;
        defect[i] = -1;
        choices[i] = 0;
        alone[i] = false;
    }
    // Where a path ends in the lockstep: its stream and its last ray as they are now (the kernels
    // go on writing its lane).
    Vec3 last_o[kPacket], last_d[kPacket];
    const auto end = [&](int i) {
        rngs[i] = Rng::from_state(a.state[i], a.inc[i]);
        last_o[i] = a.o.get(i);
        last_d[i] = a.d.get(i);
    };
    // Lane i as a State (escaped is false: an escaped path ends in the lockstep), to go on alone
    // from here: run(leave(i), &rngs[i], alone_stats[i], ...).
    const auto leave = [&](int i) -> State& {
        alone[i] = true;
        rngs[i] = Rng::from_state(a.state[i], a.inc[i]);
        new (&alone_stats[i]) PathStats;
        State* st = new (&alone_st[i]) State;
        st->o = a.o.get(i);
        st->d = a.d.get(i);
        st->medium = medium[i];
        st->weight = weight[i];
        st->skip_prim = skip_prim[i];
        st->skip = skip[i];
        st->skip_until = a.skip_until[i];
        st->defect = defect[i];
        st->depth = depth[i];
        st->random_choices = choices[i];
        return *st;
    };
    // The segment's start (begin_segment): false where the depth limit truncates the path.
    const auto begin = [&](int i) {
        if (depth[i] < options_.max_depth) return true;
        ++counts.truncated;
        lost_w[i] = weight[i];
        weight[i] = 0;
        return false;
    };
    int ids[kPacket];  // the live lanes at their segments' start, with the segments' candidates c
    Candidate c[kPacket];
    int m = 0;
    for (int i = 0; i < n; ++i) {
        ++counts.paths;
        ++counts.packet_segments;
        if (!begin(i)) {
            end(i);
            continue;
        }
        c[m] = camera[i];
        ids[m++] = i;
    }
    const double skip_floor = trace_tol::kSkipFloatUlps * trace_tol::kFloatUlp * scale_;
    while (m > 0) {
        // The interaction at each lane's candidate: mesh_only_hit's record (mesh_only_record)
        // where the kernels read it, for the lanes lanes_interact would give them.
        const LaneFace* face[kPacket];
        int k = 0;
        for (int j = 0; j < m; ++j) {
            const int i = ids[j];
            const Candidate& cj = c[j];
            if (!cj.hit) {  // interact: nothing ahead, the path leaves (branch_result looks for the display)
                ++counts.segments;
                end(i);
                continue;
            }
            const Vec3 o = a.o.get(i), d = a.d.get(i);
            const Vec3 p = o + d * cj.t;
            const Vec3& n_out = face_normals_[cj.prim];
            const double n_from = (*media_)[medium[i]].index;
            const bool in = dot(d, n_out) < 0;
            const LaneFace& f = lane_faces_[2 * static_cast<size_t>(cj.tag) + in];
            bool simple = f.simple & !f.inclusions & (depth[i] + 1 < options_.rr_depth);
            simple = simple && (is_finite(p) & is_finite(n_out) & is_finite(d) & std::isfinite(n_from));
            if (!simple) {
                // The path goes on alone from its hit, as propagate records it.
                Hit h;
                mesh_only_record(o, d, cj, h);
                h.d_in = d;
                h.length = h.t;
                h.n_from = n_from;
                run<false>(leave(i), &rngs[i], alone_stats[i], nullptr, nullptr, &h);
                continue;
            }
            if (defect[i] < 0) {  // as interact
                const int dk = medium[i].defect();
                if (dk >= 0 && scene_.defects[static_cast<size_t>(dk)].segment_min_rho2(o, p) < 1.0)
                    defect[i] = dk;
                else if (f.defect >= 0)
                    defect[i] = f.defect;
            }
            a.n_out.set(i, n_out);
            a.p.set(i, p);
            a.offset[i] = mesh_only_offset(p, cj.t);
            a.n_from[i] = n_from;
            a.n_to[i] = f.n_to;
            a.entering[i] = in ? -1 : 0;
            skip_prim[i] = cj.prim;  // the facet the spawned ray leaves (read once it is spawned)
            face[i] = &f;
            ids[k++] = i;  // k <= j: the lanes in the kernels' hands, in order
        }
        m = 0;
        if (k > 0) {
            a.d_in = a.d;
            kernels.fresnel(a, count);
            kernels.spawn(a, count, skip_floor);
            for (int j = 0; j < k; ++j) {
                const int i = ids[j];
                const LaneFace& f = *face[i];
                if (a.tir[i]) ++counts.tir;
                else ++choices[i];
                ++counts.segments;
                if (a.reflect[i]) {
                    if (!a.tir[i]) ++counts.reflections;
                } else {
                    medium[i] = f.to;
                    ++counts.transmissions;
                }
                if (!a.finite[i]) {  // spawn's check
                    ++counts.nan_events;
                    weight[i] = 0;
                    end(i);
                    continue;
                }
                skip[i] = true;
                // The next segment (run's loop): nothing ahead where the ray leaves a supporting
                // face (mesh_clear_ahead), and interact counts that segment and ends the path.
                ++depth[i];
                if (!begin(i)) {
                    end(i);
                    continue;
                }
                if (mesh_clear_ahead(skip_prim[i], a.o.get(i), a.d.get(i))) {
                    ++counts.segments;
                    end(i);
                    continue;
                }
                ids[m++] = i;
            }
        }
        if (m == 0) break;
        if (m < kMinLockstep) {  // alone from its segment's start
            run<false>(leave(ids[0]), &rngs[ids[0]], alone_stats[ids[0]], nullptr, nullptr);
            break;
        }
        EmbreeScene::PacketSkip skips;
        skips.rare = true;  // spawn's offset clears the facet (mesh_only_offset)
        for (int j = 0; j < m; ++j) {
            const int i = ids[j];
            skips.prim[j] = skip_prim[i];
            skips.on[j] = skip[i];
            skips.until[j] = a.skip_until[i];
        }
        counts.packet_segments += static_cast<std::uint64_t>(m);
        embree_->intersect_packet({a.o.x, a.o.y, a.o.z, a.d.x, a.d.y, a.d.z}, ids, m, c, &skips);
    }
    double absorbed_w[kPacket] = {};
    for (int i = 0; i < n; ++i) {
        if (alone[i]) {
            PathStats& as = alone_stats[i];
            branch_result(alone_st[i], as, out.emplace_back());
            counts.add_counters(&as, 1);
            display_w[i] = as.display_weight;
            lost_w[i] = as.lost_weight;
            absorbed_w[i] = as.absorbed_weight;
        } else {
            State st;
            st.o = last_o[i];
            st.d = last_d[i];
            st.weight = weight[i];
            st.defect = defect[i];
            st.random_choices = choices[i];
            branch_result(st, counts, display_w[i], out.emplace_back());
        }
        ends[i] = out.size();
    }
    // As merge_in_order of the paths' own counts: the counters in any order, each weight sum path
    // after path.
    stats.add_counters(&counts, 1);
    for (int i = 0; i < n; ++i) {
        stats.display_weight += display_w[i];
        stats.lost_weight += lost_w[i];
        stats.absorbed_weight += absorbed_w[i];
    }
}

}  // namespace ltm
