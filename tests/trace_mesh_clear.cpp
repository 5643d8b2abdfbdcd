// The mesh-only escape rule (Tracer::mesh_clear_ahead, geometry/Support.h): a segment the tracer
// answers "nothing ahead" without a query is one for which Embree's own query, on the same
// triangles, finds nothing either. Checked on every such segment of the camera samples of a lens
// with bubbles and of a window with a scratch (a Boolean result whose walls are not supporting
// faces), in Embree's robust and fast traversals. The rule must also fire: exits through the back
// face of a lens are its purpose. (That the answers make the same paths bit for bit, lockstep and
// one at a time, is trace_packets's test; that renders are unchanged was checked against the
// query-only tracer when the rule came in: ltm.npz byte-identical for the default and paper
// scenes, both estimators.)
#include <gtest/gtest.h>

#include <string>

#include "tests/SceneFixture.h"
#include "trace/Render.h"

using namespace ltm;

namespace {

using test::Built;
using test::build;

const char* kLens = R"(
object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
defects:
  - {type: bubble, center: [3.0, -1.0, 0.5], radius: 1.2}
  - {type: bubble, center: [-4.0, 2.0, -0.5], radius: 0.8}
camera: {resolution: [12, 12], size: [26.0, 26.0], numerical_aperture: 0.05, samples_per_pixel: 24}
display: {resolution: [40, 40], size: [90.0, 90.0], z: 55.0}
seed: 3
)";

struct Tally {
    long segments = 0, escaped = 0, embree_hits = 0;
};

Tally check(const Built& b, bool robust) {
    TracerOptions opt;
    opt.representation = Representation::MeshOnly;
    opt.robust = robust;
    const Tracer t(b.scene, b.solid, opt);
    // The tracer's Embree scene holds solid.mesh (Tracer's MeshOnly case): the same triangles.
    const EmbreeScene embree(&b.solid.mesh, nullptr, robust);
    const TelecentricCamera& cam = t.camera();
    Tally tally;
    PathStats stats;
    for (long k = 0; k < cam.pixels(); ++k)
        for_each_camera_sample(cam, b.scene.seed, k, [&](int, Rng& rng, const Vec3& o, const Vec3& d) {
            const PrincipalPath p = t.recorded_path(o, d, Medium::Air, &rng, stats);
            for (const SegmentStart& s : p.segments) {
                ++tally.segments;
                if (!s.escaped) continue;
                ++tally.escaped;
                EXPECT_TRUE(s.skip);  // the rule applies only to a ray spawned off a face
                // Embree's query with nothing skipped: not even the face just left may be met.
                const Candidate c = embree.intersect(s.o, s.d, 0.0, INFINITY);
                if (c.hit) {
                    ++tally.embree_hits;
                    ADD_FAILURE() << "pixel " << k << ": Embree meets triangle " << c.prim << " at t = " << c.t;
                }
            }
        });
    return tally;
}

TEST(MeshClear, EveryEscapedSegmentIsOneEmbreeFindsNothingOn) {
    for (const char* yaml : {kLens, test::kScratchedWindow}) {
        const Built b = build(yaml);
        for (const bool robust : {true, false}) {
            SCOPED_TRACE(std::string(yaml == kLens ? "lens" : "scratch") + (robust ? " robust" : " fast"));
            const Tally t = check(b, robust);
            EXPECT_EQ(t.embree_hits, 0);
            // Most camera samples leave the glass once through the back face (more than a few
            // percent reflect or meet a defect), and the rule answers most of those exits:
            // a sixth of all segments is a low bar (a path has about three).
            EXPECT_GT(t.escaped * 6, t.segments) << t.escaped << " of " << t.segments;
        }
    }
}

}  // namespace
