// Coherent packets (Tracer::sample_packet): a pixel's camera samples with their first segments
// found in one rtcIntersect16 give exactly what sample_paths gives one sample at a time, bit for
// bit, in every representation and with either estimator, for full and partial packets, and when
// an ellipsoid near the front face sends a ray back to the single query. Render's results are
// fixed by the same property (trace_render's determinism tests compare renders across threads).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>

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

// A window with a V scratch on its front face: the glass is a Boolean result, its first segments
// meet the scratch's walls.
const char* kScratch = R"(
object: {type: window, thickness: 5.0, diameter: 20.0, ior: 1.5}
defects:
  - {type: scratch, surface: front, profile: V, width: 0.4, depth: 0.2, start: [-4.0, -1.0], end: [4.0, 1.5]}
camera: {resolution: [8, 8], size: [10.0, 10.0], numerical_aperture: 0.02, samples_per_pixel: 16}
display: {resolution: [30, 30], size: [40.0, 40.0], z: 30.0}
seed: 4
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
    EXPECT_EQ(packet_stats.paths, single_stats.paths);
    EXPECT_EQ(packet_stats.segments, single_stats.segments);
    EXPECT_EQ(packet_stats.on_display, single_stats.on_display);
    EXPECT_EQ(packet_stats.leaks_unresolved, single_stats.leaks_unresolved);
    return packet_stats;
}

Tracer make(const Built& b, Representation r) {
    TracerOptions o;
    o.representation = r;
    return Tracer(b.scene, b.solid, o);
}

}  // namespace

TEST(Packets, RefinedAndMeshOnlyUsePacketsAndMatchSingleRaysBitForBit) {
    const Built b = build(kLens);
    for (auto r : {Representation::Refined, Representation::MeshOnly}) {
        SCOPED_TRACE(to_string(r));
        const Tracer t = make(b, r);
        ASSERT_TRUE(t.packets());  // Debian's Embree honours ray masks: packets are on
        for (int size : {Tracer::kPacket, 5}) {
            const PathStats s = expect_packets_match(t, size);
            EXPECT_GT(s.packet_segments, 0u);
            // Every first segment went one of the two ways (a partial packet of one goes alone).
            if (size == Tracer::kPacket) {
                EXPECT_EQ(s.packet_segments + s.packet_fallbacks, s.paths);
            }
        }
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
    expect_packets_match(make(lens, Representation::Refined), Tracer::kPacket);
    const Built scratch = build(kScratch);
    for (auto r : {Representation::Refined, Representation::MeshOnly}) {
        SCOPED_TRACE(to_string(r));
        expect_packets_match(make(scratch, r), Tracer::kPacket);
    }
}

TEST(Packets, AnalyticTracesOneRayAtATimeWithTheSameResults) {
    const Built b = build(kLens);
    const Tracer t = make(b, Representation::Analytic);
    EXPECT_FALSE(t.packets());
    const PathStats s = expect_packets_match(t, Tracer::kPacket);
    EXPECT_EQ(s.packet_segments, 0u);
}

TEST(Packets, APacketHoldsAtMostSixteenSamples) {
    const Built b = build(kLens);
    const Tracer t = make(b, Representation::Refined);
    std::vector<Vec3> o(17), d(17, Vec3{0, 0, 1});
    std::vector<Rng> r(17, Rng(1, 2, 3));
    std::vector<PathResult> out;
    size_t ends[17];
    EXPECT_THROW(t.sample_packet(17, o.data(), d.data(), r.data(), *std::make_unique<PathStats>(), out, ends),
                 std::invalid_argument);
}
