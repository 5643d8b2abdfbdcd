#pragma once
// Where a render's time goes, per path and per stage, measured by replaying
// each stage's own work in isolation on one thread and comparing it with a one-thread render of
// the same scene. The production code carries no timers: each stage is timed on the render's own
// inputs, recorded from the render's own paths, and scaled to the render's counts.
//
//   camera        for_each_camera_sample over every pixel: the stream per sample, the stratified
//                 position, the direction on the aperture disc (Camera.h);
//   intersection  bare Embree calls on the mesh-only representation's triangles, as the render
//                 makes them: the camera segments in the render's batches of 64, regrouped by
//                 octant into packets of 16 (EmbreeScene::intersect_coherent: rtcIntersect16,
//                 coherent) where the tracer uses packets (Tracer::packets); the later segments
//                 one rtcIntersect1 each, or, where the paths go side by side (Tracer::lockstep),
//                 a packet's paths at one depth in one intersect_packet (rtcIntersect16 with the
//                 skip filter) and an escaped segment none (the mesh representations; 0 for
//                 analytic, which calls no BVH for the object's faces);
//   hit           Tracer::first_hits on the camera segments (in packets, as the render) and
//                 Tracer::first_hit on every other recorded segment from its recorded start: the
//                 representation's whole "next interface" step (Embree's candidates with the skip
//                 filter, the analytic refinement and exact guard, the normal and spawn offset; for
//                 analytic the patch tests), minus the intersection above;
//   fresnel+rng   fresnel(), refract or reflect, normalize and one uniform draw per interaction;
//   accumulate    merge_row() of each pixel's entries (the render's per-row sort and sum);
//   merge         the render's serial CSR assembly (RenderResult::merge_seconds, measured inside);
//   loop          the rest of the render: the integrator loop around these stages (state, spawn,
//                 roulette, statistics, the display hit, tbb), the render minus the stages above.
// Computing the features from T, and writing (the ltm.npz archive, features.exr), are timed apart,
// per path of the render.
//
// Replays are cyclic over the recorded workload (a spread of `record_pixels` pixels, every
// sample's sampled path, exactly as the render draws it), so a stage's cost per item is the
// average over a representative mix, not a single ray repeated.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/BenchSupport.h"
#include "features/Features.h"
#include "io/Image.h"
#include "io/LtmFile.h"
#include "trace/Optics.h"
#include "trace/Render.h"

namespace ltm::bench {

struct StageTimes {
    double render = 0, camera = 0, intersection = 0, hit = 0, fresnel = 0, accumulate = 0, merge = 0, features = 0,
           write = 0;
    std::uint64_t paths = 0, segments = 0, interactions = 0;
    bool lockstep = false;  // the render traced paths side by side (Tracer::lockstep)
    double loop() const { return render - camera - intersection - hit - fresnel - accumulate - merge; }
};

namespace detail {

struct Interaction {
    Vec3 d, n;  // incident direction, unit normal on the incident side
    double eta;
};

// The render's own sampled paths for a spread of pixels: their segments with media, their
// interactions, and each pixel's row entries.
struct Workload {
    // Camera segments (the first of each path, a pixel's samples consecutive, so that replays in
    // batches of 64 see the render's batches), and the rest.
    std::vector<Vec3> camera_o, camera_d;
    std::vector<SegmentStart> segments;
    std::vector<std::uint32_t> segment_path;  // per segment: its path (index into camera_o)
    std::vector<std::uint32_t> segment_depth;  // and its place in that path (1: after the camera's)
    std::vector<Interaction> interactions;
    std::vector<std::vector<RowEntry>> rows;
};

inline Workload record(const Tracer& t, long record_pixels) {
    Workload w;
    const TelecentricCamera& cam = t.camera();
    const long K = cam.pixels();
    const std::uint64_t seed = t.scene().seed;
    PathStats stats;
    std::vector<PathResult> branches;
    for (long i = 0; i < record_pixels; ++i) {
        const long k = (i * K) / record_pixels + K / (2 * record_pixels);
        std::vector<RowEntry> row;
        for_each_camera_sample(cam, seed, k, [&](int, Rng& rng, const Vec3& o, const Vec3& d) {
            Rng replay = rng;
            const PrincipalPath p = t.recorded_path(o, d, Medium::Air, &replay, stats);
            w.camera_o.push_back(p.segments.front().o);
            w.camera_d.push_back(p.segments.front().d);
            for (size_t j = 1; j < p.segments.size(); ++j) {
                w.segments.push_back(p.segments[j]);
                w.segment_path.push_back(static_cast<std::uint32_t>(w.camera_o.size() - 1));
                w.segment_depth.push_back(static_cast<std::uint32_t>(j));
            }
            for (size_t v = 0; v < p.vertices.size(); ++v) {
                const Vec3& dir = p.segments[v].d;
                const Vec3 n = t.solid().surfaces[p.tags[v]].surface.normal(p.vertices[v]);
                const Vec3 nf = dot(dir, n) < 0 ? n : -n;
                const double eta = t.media()[p.media[v]].index / t.media()[p.media[std::min(v + 1, p.media.size() - 1)]].index;
                w.interactions.push_back({dir, nf, eta});
            }
            branches.clear();
            t.sample_paths(o, d, rng, stats, branches);
            for (const PathResult& r : branches)
                if (r.pixel >= 0) row.push_back({static_cast<std::int32_t>(r.pixel), r.weight});
        });
        w.rows.push_back(std::move(row));
    }
    return w;
}

template <class F>
double seconds_of(int reps, F&& f) {
    std::vector<double> times;
    for (int i = 0; i < reps; ++i) {
        const double t0 = now();
        f();
        times.push_back(now() - t0);
    }
    return median(times);
}

}  // namespace detail

// The breakdown of one representation's render of `tracer`'s scene on one thread. `mesh_only`:
// a tracer of the same solid in the mesh-only representation (its Embree scene is the triangles
// alone, the bare baseline's); `out_dir`: where the write stage writes (removed afterwards).
inline StageTimes stage_breakdown(const Tracer& tracer, const Tracer& mesh_only, int reps, const std::string& out_dir,
                                  long record_pixels = 400) {
    using namespace detail;
    StageTimes st;
    st.lockstep = tracer.lockstep();
    RenderResult r;
    std::vector<double> renders, merges;
    for (int i = 0; i < reps; ++i) {
        RenderOptions ro;
        ro.threads = 1;
        r = render(tracer, ro);
        renders.push_back(r.seconds);
        merges.push_back(r.merge_seconds);
    }
    st.render = median(renders);
    st.merge = median(merges);
    st.paths = r.stats.paths;
    st.segments = r.stats.segments;
    st.interactions = r.stats.reflections + r.stats.transmissions + r.stats.tir + r.stats.splits;

    const TelecentricCamera& cam = tracer.camera();
    const std::uint64_t seed = tracer.scene().seed;
    double sink = 0;
    st.camera = seconds_of(reps, [&] {
        for (long k = 0; k < cam.pixels(); ++k)
            for_each_camera_sample(cam, seed, k, [&](int, Rng& rng, const Vec3& o, const Vec3& d) {
                sink += o.x + d.x + static_cast<double>(rng.uniform() > 2.0);
            });
    });

    const Workload w = record(tracer, record_pixels);
    const std::uint64_t S = st.segments, I = st.interactions, P = st.paths;
    // The camera segments in the render's batches: P of them, 64 at a time (the last of a pixel's
    // batches may be partial in the render; here they run cyclically through the recorded ones).
    const size_t nc = w.camera_o.size();
    const auto batches_of = [&](auto&& f) {
        for (std::uint64_t j = 0; j < P; j += Tracer::kBatch) {
            const size_t a = static_cast<size_t>(j % nc);
            const int n = static_cast<int>(std::min<std::uint64_t>({Tracer::kBatch, P - j, nc - a}));
            f(a, n);
        }
    };
    if (tracer.representation() != Representation::Analytic)
        st.intersection = seconds_of(reps, [&] {
            long hits = 0;
            Candidate c[Tracer::kBatch];
            batches_of([&](size_t a, int n) {
                if (tracer.packets() && n >= 2) {
                    mesh_only.embree().intersect_coherent(&w.camera_o[a], &w.camera_d[a], n, c);
                    for (int i = 0; i < n; ++i) hits += c[i].hit;
                } else {
                    for (int i = 0; i < n; ++i) hits += mesh_only.embree().raw_intersect(w.camera_o[a + i], w.camera_d[a + i], 0.0f) >= 0;
                }
            });
            if (!tracer.lockstep()) {
                for (std::uint64_t j = 0; j + P < S; ++j) {
                    const SegmentStart& s = w.segments[j % w.segments.size()];
                    hits += mesh_only.embree().raw_intersect(s.o, s.d, 0.0f) >= 0;
                }
            }
            sink += static_cast<double>(hits);
        });
    if (tracer.representation() != Representation::Analytic && tracer.lockstep() && !w.segments.empty()) {
        // The lockstep render queries the later segments as it goes: those of one packet of
        // kPacket paths at the same depth together (intersect_packet, with each ray's skip), fewer
        // than kMinLockstep one by one, and an escaped one (nothing of the object ahead) not at
        // all. Replayed so from the recorded paths, once through, scaled to the render's S - P.
        std::vector<std::vector<size_t>> packets;  // indices into w.segments
        {
            std::vector<std::vector<size_t>> by_depth;
            size_t j = 0;
            for (size_t g = 0; g < nc; g += Tracer::kPacket) {
                by_depth.clear();
                for (; j < w.segments.size() && w.segment_path[j] < g + Tracer::kPacket; ++j) {
                    if (w.segments[j].escaped) continue;
                    const size_t depth = w.segment_depth[j];
                    if (by_depth.size() < depth) by_depth.resize(depth);
                    by_depth[depth - 1].push_back(j);
                }
                for (auto& p : by_depth)
                    if (!p.empty()) packets.push_back(std::move(p));
            }
        }
        const double scale = static_cast<double>(S - P) / static_cast<double>(w.segments.size());
        st.intersection += scale * seconds_of(reps, [&] {
            long hits = 0;
            Vec3 o[Tracer::kPacket], d[Tracer::kPacket];
            Candidate c[Tracer::kPacket];
            EmbreeScene::PacketSkip skip;
            for (const auto& p : packets) {
                const int q = static_cast<int>(p.size());
                if (q < Tracer::kMinLockstep) {
                    for (size_t j : p) hits += mesh_only.embree().raw_intersect(w.segments[j].o, w.segments[j].d, 0.0f) >= 0;
                    continue;
                }
                for (int i = 0; i < q; ++i) {
                    const SegmentStart& s = w.segments[p[static_cast<size_t>(i)]];
                    o[i] = s.o;
                    d[i] = s.d;
                    skip.prim[i] = s.skip_prim;
                    skip.on[i] = s.skip;
                    skip.until[i] = s.skip_until;
                }
                mesh_only.embree().intersect_packet(o, d, q, c, &skip);
                for (int i = 0; i < q; ++i) hits += c[i].hit;
            }
            sink += static_cast<double>(hits);
        });
    }
    PathStats scratch;
    st.hit = seconds_of(reps, [&] {
                 Tracer::FirstHit f[Tracer::kBatch];
                 batches_of([&](size_t a, int n) {
                     tracer.first_hits(n, &w.camera_o[a], &w.camera_d[a], f, scratch);
                     sink += f[0].t;
                 });
                 for (std::uint64_t j = 0; j + P < S; ++j) sink += tracer.first_hit(w.segments[j % w.segments.size()], scratch).t;
             }) -
             st.intersection;
    st.fresnel = seconds_of(reps, [&] {
        Rng rng(seed, 1, 2);
        for (std::uint64_t j = 0; j < I && !w.interactions.empty(); ++j) {
            const Interaction& x = w.interactions[j % w.interactions.size()];
            const double cos_i = -dot(x.d, x.n);
            const FresnelResult F = fresnel(cos_i, x.eta);
            const Vec3 nd = rng.uniform() < F.reflectance ? reflect(x.d, x.n) : refract(x.d, x.n, x.eta, cos_i, F.cos_t);
            sink += normalize(nd).z;
        }
    });
    st.accumulate = seconds_of(reps, [&] {
        std::vector<RowEntry> entries;
        std::vector<std::int32_t> columns;
        std::vector<float> values;
        for (long k = 0; k < cam.pixels(); ++k) {
            const auto& e = w.rows[static_cast<size_t>(k) % w.rows.size()];
            entries.assign(e.begin(), e.end());
            columns.clear();
            values.clear();
            sink += merge_row(entries, cam.samples_per_pixel(), columns, values);
        }
    });

    // After the render, apart from it: computing the features from T, then writing the archive
    // and the features' EXR (previews are timed by `ltmsim render --verbose`'s stages, not here).
    std::filesystem::create_directories(out_dir);
    const Display& disp = tracer.display();
    FeatureImages f;
    st.features = seconds_of(reps, [&] {
        FeatureOptions fo;
        f = compute_features(r.T, tracer.scene().camera.resolution[0], tracer.scene().camera.resolution[1],
                             {disp.Q, disp.P, disp.width, disp.height}, fo);
    });
    st.write = seconds_of(reps, [&] {
        write_ltm_npz(out_dir + "/ltm.npz", r.T);
        write_exr(out_dir + "/features.exr", f.width, f.height, f.channels);
    });
    std::filesystem::remove_all(out_dir);
    if (sink == 0.123456789) std::printf(" ");  // keeps the replays' results alive
    return st;
}

inline void print_stage_breakdown(const char* repr, const StageTimes& s) {
    const double P = static_cast<double>(s.paths);
    const auto ns = [&](double sec) { return 1e9 * sec / P; };
    const auto pc = [&](double sec) { return 100.0 * sec / s.render; };
    std::printf("%-10s %8.0f ns/path (%.2f segments, %.2f interactions per path)\n", repr, ns(s.render), s.segments / P,
                s.interactions / P);
    const std::pair<const char*, double> rows[] = {{"camera", s.camera},         {"intersection", s.intersection},
                                                   {"hit", s.hit},               {"fresnel+rng", s.fresnel},
                                                   {"accumulate", s.accumulate}, {"merge", s.merge},
                                                   {"loop", s.loop()}};
    for (const auto& [name, sec] : rows) std::printf("  %-14s %8.1f ns %6.1f %%\n", name, ns(sec), pc(sec));
    std::printf("  %-14s %8.1f ns %6.1f %% of the render (not in it)\n", "features", ns(s.features), pc(s.features));
    std::printf("  %-14s %8.1f ns %6.1f %% of the render (not in it)\n", "write", ns(s.write), pc(s.write));
    if (s.lockstep)
        std::printf("  (lockstep render: hit and fresnel+rng replay the scalar steps, which the render does\n"
                    "   mostly in SIMD lanes, so they overstate those stages and loop may be negative)\n");
}

}  // namespace ltm::bench
