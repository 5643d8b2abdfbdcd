// Coherent packets (Tracer::sample_packet): a pixel's camera samples with their first segments
// found in one rtcIntersect16, and (Tracer::lockstep) traced side by side with every later
// segment's candidates from one packet too, give exactly what sample_paths gives one sample at a
// time, bit for bit, in every representation and with either estimator, for full and partial packets, and when
// an ellipsoid near the front face sends a ray back to the single query. Render's results are
// fixed by the same property (trace_render's determinism tests compare renders across threads).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <vector>

#include "tests/SceneFixture.h"
#include "trace/Render.h"

using namespace ltm;

namespace {

using test::Built;
using test::build;

// A plano-convex lens with a bubble, an absorbing particle and a second bubble so close under the
// front vertex (z = -3.5) that its bounding sphere reaches out of the glass: camera rays near the
// axis pass it before they meet the front face's facets, so a packet's triangle candidate is not
// the full query's answer there and those rays must query alone (PathStats::packet_fallbacks).
const char* kLens = R"(
object: {type: lens, r1: 40.0, r2: inf, center_thickness: 7.0, diameter: 24.0, ior: 1.72}
defects:
  - {type: bubble, center: [3.0, -1.0, 0.5], radius: 1.2}
  - {type: particle, center: [-5.0, 3.0, 1.0], radius: 0.7}
  - {type: bubble, center: [0.0, 0.0, -2.6], radius: 0.6}
camera: {resolution: [9, 9], size: [25.0, 25.0], numerical_aperture: 0.04, samples_per_pixel: 37}
display: {resolution: [40, 40], size: [90.0, 90.0], z: 55.0}
seed: 9
)";

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every pixel's samples through sample_packet in packets of `size`, against sample_paths one by
// one on copies of the same streams; returns the stats of the packet run.
PathStats expect_packets_match(const Tracer& t, int size) {
    const TelecentricCamera& cam = t.camera();
    PathStats single_stats, packet_stats;
    for (long k = 0; k < cam.pixels(); ++k) {
        std::vector<Vec3> o, d;
        std::vector<Rng> single, packed;
        for_each_camera_sample(cam, t.scene().seed, k, [&](int, Rng& rng, const Vec3& a, const Vec3& b) {
            o.push_back(a);
            d.push_back(b);
            single.push_back(rng);
            packed.push_back(rng);
        });
        std::vector<PathResult> want, got;
        std::vector<size_t> want_end, got_end(o.size());
        for (size_t s = 0; s < o.size(); ++s) {
            t.sample_paths(o[s], d[s], single[s], single_stats, want);
            want_end.push_back(want.size());
        }
        for (size_t s = 0; s < o.size(); s += static_cast<size_t>(size)) {
            const int n = static_cast<int>(std::min(o.size() - s, static_cast<size_t>(size)));
            t.sample_packet(n, &o[s], &d[s], &packed[s], packet_stats, got, &got_end[s]);
        }
        EXPECT_EQ(got_end, want_end) << "pixel " << k;
        EXPECT_EQ(got.size(), want.size());
        for (size_t i = 0; i < std::min(want.size(), got.size()); ++i) {
            EXPECT_EQ(got[i].pixel, want[i].pixel) << "pixel " << k << " branch " << i;
            EXPECT_TRUE(same_bits(got[i].weight, want[i].weight)) << "pixel " << k << " branch " << i;
            EXPECT_EQ(got[i].defect, want[i].defect);
            EXPECT_EQ(got[i].random_choices, want[i].random_choices);
        }
        // Each stream is left where the single path left it.
        for (size_t s = 0; s < o.size(); ++s) EXPECT_TRUE(same_bits(packed[s].uniform(), single[s].uniform()));
    }
    // Every counter (but the packet counters themselves, which one-at-a-time paths leave at 0).
    const auto counters = [](const PathStats& p) {
        return std::vector<std::uint64_t>{p.paths, p.segments, p.reflections, p.transmissions, p.tir,
                                          p.absorbed_particle, p.absorbed_rim, p.on_display, p.off_display,
                                          p.toward_camera, p.roulette_kills, p.truncated, p.nan_events, p.splits,
                                          p.branches,
                                          // The same candidates: a packet that did not skip the facet a ray
                                          // just left would hand refined_hit a spurious candidate the single
                                          // query never sees.
                                          p.spurious_candidates, p.guard_hits, p.leak_retries, p.leaks_unresolved,
                                          p.seam_repairs, p.edge_chords, p.grin_segments, p.grin_evaluations,
                                          p.tet_crossings, p.lost, p.hamiltonian_violations, p.walk_boundary_exits};
    };
    EXPECT_EQ(counters(packet_stats), counters(single_stats));
    // The weight sums too, bit for bit: paths traced side by side (Tracer::sample_lockstep) are
    // summed in sample order after the packet, as one path after another adds to them.
    EXPECT_TRUE(same_bits(packet_stats.display_weight, single_stats.display_weight));
    EXPECT_TRUE(same_bits(packet_stats.absorbed_weight, single_stats.absorbed_weight));
    EXPECT_TRUE(same_bits(packet_stats.lost_weight, single_stats.lost_weight));
    return packet_stats;
}

Tracer make(const Built& b, Representation r, int max_depth = TracerOptions{}.max_depth) {
    TracerOptions o;
    o.representation = r;
    o.max_depth = max_depth;
    return Tracer(b.scene, b.solid, o);
}

}  // namespace

TEST(Packets, RefinedAndMeshOnlyUsePacketsAndMatchSingleRaysBitForBit) {
    const Built b = build(kLens);
    for (auto r : {Representation::Refined, Representation::MeshOnly}) {
        SCOPED_TRACE(to_string(r));
        const Tracer t = make(b, r);
        ASSERT_TRUE(t.packets());  // Debian's Embree honours ray masks: packets are on
        ASSERT_TRUE(t.lockstep());  // the sample estimator, no absorption: whole paths side by side
        for (int size : {Tracer::kBatch, Tracer::kPacket + 1, Tracer::kPacket, 5}) {
            const PathStats s = expect_packets_match(t, size);
            EXPECT_GT(s.packet_segments, 0u);
            // Every first segment went one of the two ways, and so did later ones: packet
            // candidates answered more segments than there are camera rays.
            EXPECT_GT(s.packet_segments + s.packet_fallbacks, s.paths);
            EXPECT_LE(s.packet_segments + s.packet_fallbacks, s.segments);
        }
    }
}

// Paths cut by the depth cap (their weight counted as lost) and paths that end on the absorbing
// particle (as absorbed) add to the weight sums at their ends: side by side, the sums are still
// the one-at-a-time sums bit for bit.
TEST(Packets, TruncatedAndAbsorbedPathsSumTheirWeightsAsOneAtATime) {
    const Built b = build(kLens);
    for (auto r : {Representation::Refined, Representation::MeshOnly}) {
        SCOPED_TRACE(to_string(r));
        const Tracer t = make(b, r, 2);
        ASSERT_TRUE(t.lockstep());
        const PathStats s = expect_packets_match(t, Tracer::kPacket);
        EXPECT_GT(s.truncated, 0u);
        EXPECT_GT(s.lost_weight, 0.0);
        EXPECT_GT(s.absorbed_particle, 0u);
    }
}

// Absorption in the glass adds to the absorbed weight on every segment: those paths take the
// first segment from the packet only, and match all the same.
TEST(Packets, AbsorbingGlassTracesOnlyTheFirstSegmentsInPackets) {
    Built b = build(kLens);
    b.scene.object.absorption = 0.05;
    for (auto r : {Representation::Refined, Representation::MeshOnly}) {
        SCOPED_TRACE(to_string(r));
        const Tracer t = make(b, r);
        EXPECT_TRUE(t.packets());
        EXPECT_FALSE(t.lockstep());
        const PathStats s = expect_packets_match(t, Tracer::kPacket);
        EXPECT_EQ(s.packet_segments + s.packet_fallbacks, s.paths);
        EXPECT_GT(s.absorbed_weight, 0.0);
    }
}

TEST(Packets, AnEllipsoidBeforeTheFrontFaceSendsItsRaysToTheSingleQuery) {
    const Built b = build(kLens);
    const Tracer t = make(b, Representation::Refined);
    const PathStats s = expect_packets_match(t, Tracer::kPacket);
    // The near bubble's bounding sphere (radius 0.6 sqrt 3 = 1.04 about z = -2.6) reaches out of
    // the front vertex (0.9 away): the axial pixel's rays pass it.
    EXPECT_GT(s.packet_fallbacks, 0u);
}

TEST(Packets, SplitEstimatorAndBooleanGlassMatchToo) {
    Built lens = build(kLens);
    lens.scene.tracing.estimator = Estimator::Split;
    lens.scene.tracing.split_depth = 3;
    const Tracer split = make(lens, Representation::Refined);
    EXPECT_FALSE(split.lockstep());  // a split sample's branches go one after another
    expect_packets_match(split, Tracer::kPacket);
    const Built scratch = build(test::kScratchedWindow);
    for (auto r : {Representation::Refined, Representation::MeshOnly}) {
        SCOPED_TRACE(to_string(r));
        expect_packets_match(make(scratch, r), Tracer::kPacket);
    }
}

// The analytic representation has no packet query: its paths go side by side with the object's
// patches solved in SIMD lanes (trace/Lanes.h), and the rest (the bubbles near a segment, rim
// hits, roulette, the depth cap, total internal reflection) in the scalar steps.
TEST(Packets, AnalyticTracesWholePathsInSimdLanesWithTheSameResults) {
    const Built b = build(kLens);
    for (int max_depth : {TracerOptions{}.max_depth, 2}) {
        SCOPED_TRACE(max_depth);
        const Tracer t = make(b, Representation::Analytic, max_depth);
        EXPECT_FALSE(t.packets());
        ASSERT_TRUE(t.lockstep());
        for (int size : {Tracer::kBatch, Tracer::kPacket + 1, Tracer::kPacket, 5}) {
            const PathStats s = expect_packets_match(t, size);
            EXPECT_EQ(s.packet_segments, 0u);
            EXPECT_GT(s.absorbed_particle, 0u);
            if (max_depth == 2) {
                EXPECT_GT(s.truncated, 0u);
            }
        }
    }
}

// A ball lens (two hemispheres of one sphere, no rim) and a window (plane caps) with a bubble:
// rays reflected inside the ball meet total internal reflection, and Russian roulette from the
// second interaction on kills some paths; every lane still matches its path traced alone, in the
// analytic lanes and in the mesh-only ones (whose lanes leave the lockstep where roulette begins).
TEST(Packets, LanesMatchOnBallsWindowsAndUnderRoulette) {
    const char* ball = R"(
object: {type: sphere, radius: 6.0, ior: 1.9}
defects:
  - {type: bubble, center: [1.0, 0.5, 0.0], radius: 0.8}
camera: {resolution: [7, 7], size: [13.0, 13.0], numerical_aperture: 0.05, samples_per_pixel: 24}
display: {resolution: [30, 30], size: [60.0, 60.0], z: 40.0}
seed: 5
)";
    const char* window = R"(
object: {type: window, thickness: 5.0, diameter: 20.0, ior: 1.5}
defects:
  - {type: bubble, center: [2.0, -1.0, 0.0], radius: 1.0}
camera: {resolution: [6, 6], size: [22.0, 22.0], numerical_aperture: 0.03, samples_per_pixel: 16}
display: {resolution: [30, 30], size: [40.0, 40.0], z: 30.0}
seed: 6
)";
    for (const char* yaml : {ball, window}) {
        const Built b = build(yaml);
        for (auto r : {Representation::Analytic, Representation::MeshOnly}) {
            SCOPED_TRACE(to_string(r));
            TracerOptions o;
            o.representation = r;
            o.rr_depth = 2;
            const Tracer t(b.scene, b.solid, o);
            ASSERT_TRUE(t.lockstep());
            const PathStats s = expect_packets_match(t, Tracer::kPacket);
            EXPECT_GT(s.roulette_kills, 0u);
            if (yaml == ball) {
                EXPECT_GT(s.tir, 0u);
            }
        }
    }
}

TEST(Packets, ABatchHoldsAtMostSixtyFourSamples) {
    const Built b = build(kLens);
    const Tracer t = make(b, Representation::Refined);
    constexpr int n = Tracer::kBatch + 1;
    static_assert(Tracer::kBatch == 64, "the test's name");
    std::vector<Vec3> o(n), d(n, Vec3{0, 0, 1});
    std::vector<Rng> r(n, Rng(1, 2, 3));
    std::vector<PathResult> out;
    size_t ends[n];
    EXPECT_THROW(t.sample_packet(n, o.data(), d.data(), r.data(), *std::make_unique<PathStats>(), out, ends),
                 std::invalid_argument);
}

// EmbreeScene::intersect_coherent regroups rays by the octant of their direction: whatever the
// grouping, each ray gets its own answer, in its own slot. Rays from all eight octants, through
// and beside the lens (from a box around it, so that some start inside the glass), in batches of
// every size that exercises a path of the regrouping: none, one, a partial packet, whole packets
// with remainders, and more than the 256 its order array holds on the stack. Each answer must be
// the single-ray query's (hit, facet and float distance); a ray exactly through an edge, where
// the two may differ, has probability zero among these.
TEST(Packets, CoherentQueriesGiveEachRayItsOwnAnswer) {
    const Built b = build(kLens);
    const Tracer t = make(b, Representation::MeshOnly);
    const EmbreeScene& e = t.embree();
    Rng rng(5, 6, 7);
    std::vector<Vec3> o, d;
    for (int i = 0; i < 700; ++i) {
        o.push_back({24 * rng.uniform() - 12, 24 * rng.uniform() - 12, 12 * rng.uniform() - 8});
        d.push_back(normalize(Vec3{2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1}));
    }
    long hits = 0;
    for (int n : {0, 1, 7, 16, 17, 64, 100, 700}) {
        std::vector<Candidate> got(static_cast<size_t>(n));
        e.intersect_coherent(o.data(), d.data(), n, got.data());
        for (int i = 0; i < n; ++i) {
            const Candidate want = e.intersect(o[static_cast<size_t>(i)], d[static_cast<size_t>(i)], 0.0, INFINITY);
            const Candidate& c = got[static_cast<size_t>(i)];
            ASSERT_EQ(c.hit, want.hit) << "batch " << n << " ray " << i;
            if (!want.hit) continue;
            ++hits;
            EXPECT_EQ(c.prim, want.prim) << "batch " << n << " ray " << i;
            EXPECT_EQ(c.tag, want.tag);
            EXPECT_TRUE(same_bits(c.t, want.t)) << "batch " << n << " ray " << i;
        }
    }
    EXPECT_GT(hits, 300);  // most rays meet the lens or a defect's shell: the answers are not all misses
}

// EmbreeScene::intersect_packet's skip list, traced with the filter on every hit or (rare, as the
// mesh-only lockstep asks) without it and again with it for the rays that met their skipped
// facet: either way each ray gets the single query's answer with the same skip list of one.
// Rays aimed at a facet's centroid from 1e-4 mm before it, in all directions: with the facet
// skipped within 1e-3 mm the answer must lie beyond it (the facet met first, then traced again);
// within 1e-5 mm the facet itself is the answer; unskipped rays see it too. Batches of one ray,
// of five (a partial packet) and of a whole packet.
TEST(Packets, SkippedFacetsAreSkippedWithOrWithoutTheFilterOnEveryHit) {
    const Built b = build(kLens);
    const Tracer t = make(b, Representation::MeshOnly);
    const EmbreeScene& e = t.embree();
    const TriMesh& mesh = b.solid.mesh;
    Rng rng(11, 12, 13);
    constexpr int kRays = 400;
    std::vector<Vec3> o, d;
    std::vector<std::uint32_t> facet;
    std::vector<double> until;
    std::vector<bool> on;
    for (int i = 0; i < kRays; ++i) {
        const auto f = static_cast<std::uint32_t>(rng.uniform() * static_cast<double>(mesh.num_triangles()));
        const auto& tri = mesh.triangles[f];
        const Vec3 c = (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) * (1.0 / 3);
        const Vec3 dir = normalize(Vec3{2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1});
        o.push_back(c - dir * 1e-4);
        d.push_back(dir);
        facet.push_back(f);
        until.push_back(i % 3 == 0 ? 1e-3 : 1e-5);
        on.push_back(i % 3 != 2);
    }
    long skipped = 0, kept = 0;
    for (bool rare : {false, true})
        for (int n : {1, 5, EmbreeScene::kPacket}) {
            for (int s = 0; s + n <= kRays; s += n) {
                EmbreeScene::PacketSkip skip;
                skip.rare = rare;
                for (int j = 0; j < n; ++j) {
                    skip.prim[j] = facet[static_cast<size_t>(s + j)];
                    skip.on[j] = on[static_cast<size_t>(s + j)];
                    skip.until[j] = until[static_cast<size_t>(s + j)];
                }
                Candidate got[EmbreeScene::kPacket];
                e.intersect_packet(&o[static_cast<size_t>(s)], &d[static_cast<size_t>(s)], n, got, &skip);
                for (int j = 0; j < n; ++j) {
                    const auto i = static_cast<size_t>(s + j);
                    const Candidate want = on[i] ? e.intersect(o[i], d[i], 0.0, INFINITY, &facet[i], 1, until[i])
                                                 : e.intersect(o[i], d[i], 0.0, INFINITY);
                    const Candidate& c = got[j];
                    ASSERT_EQ(c.hit, want.hit) << "rare " << rare << " batch " << n << " ray " << i;
                    if (!want.hit) continue;
                    EXPECT_EQ(c.prim, want.prim) << "rare " << rare << " batch " << n << " ray " << i;
                    EXPECT_TRUE(same_bits(c.t, want.t)) << "rare " << rare << " batch " << n << " ray " << i;
                    if (on[i] && until[i] > 1e-4) {
                        EXPECT_NE(c.prim, facet[i]) << "ray " << i;  // skipped: the answer lies beyond
                        ++skipped;
                    } else if (c.prim == facet[i]) {
                        ++kept;
                    }
                }
            }
        }
    // Both ways were taken: facets met and skipped (for rare: traced again), and facets answered.
    EXPECT_GT(skipped, 100);
    EXPECT_GT(kept, 200);
}
