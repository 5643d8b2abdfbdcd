// The defect-free reference of the deflection map (study/SceneRun.h): rendered at every pixel with
// random numbers of its own, as a separately measured golden sample would be, so the deflection
// map shows noise away from the defects instead of an exact 0; bit-identical for any thread count.
// Shared between scenes (study/ReferenceCache.h), it must never change a result: scenes with the
// same object, camera, display and seed, run through one cache, give bit for bit the reference and
// the deflection images each gives alone, and only the first renders it. Scenes whose key differs
// (another seed, another object) share nothing.
#include <gtest/gtest.h>

#include <string>

#include "study/SceneRun.h"
#include "tests/SceneFixture.h"

using namespace ltm;

namespace {

// A window with bubbles at `defects` (YAML list items), 24 x 24 camera pixels over 12 mm.
std::string window_scene(const std::string& defects, int seed = 3, double ior = 1.5) {
    return "object: {type: window, thickness: 4.0, diameter: 20.0, ior: " + std::to_string(ior) +
           "}\n"
           "defects:" +
           (defects.empty() ? std::string(" []\n") : "\n" + defects) +
           "camera: {resolution: [24, 24], size: [12.0, 12.0], numerical_aperture: 0.02, samples_per_pixel: 8}\n"
           "display: {resolution: [60, 60], size: [30.0, 30.0], z: 30.0}\n"
           "seed: " + std::to_string(seed) + "\n";
}
const std::string kBubbleA = "  - {type: bubble, center: [-2.0, 1.0, 0.0], radius: 0.8}\n";
const std::string kBubbleB = "  - {type: bubble, center: [-1.5, 1.0, 0.5], radius: 0.6}\n";

SceneRun run(const test::Built& b, ReferenceCache* cache, int threads = 2) {
    SceneRunOptions o;
    o.representation = auto_representation(b.solid);
    o.threads = threads;
    o.reference_cache = cache;
    return run_scene(b.scene, b.solid, o, nullptr);
}

// Bit for bit: NaN (an empty row) on both sides, or the same float.
bool same(float a, float b) { return (a != a && b != b) || a == b; }

void expect_same_reference(const SceneRun& alone, const SceneRun& shared) {
    ASSERT_EQ(alone.reference.size(), shared.reference.size());
    for (size_t i = 0; i < alone.reference.size(); ++i)
        EXPECT_TRUE(same(alone.reference[i], shared.reference[i])) << "value " << i << ": " << alone.reference[i] << " vs "
                                                                   << shared.reference[i];
    for (const char* ch : {"DeflectionX", "DeflectionY", "Deflection"}) {
        const auto& a = alone.features.channel(ch);
        const auto& b = shared.features.channel(ch);
        for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(same(a[i], b[i])) << ch << " " << i;
    }
}

}  // namespace

TEST(Reference, IsTheDefectFreeObjectRenderedWithItsOwnRandomNumbers) {
    const test::Built a = test::build(window_scene(kBubbleA));
    const SceneRun r = run(a, nullptr);
    const long K = 24 * 24;
    EXPECT_EQ(r.reference_pixels, K);
    // The reference is the defect-free scene's own MeanX and MeanY when that scene is rendered
    // with seed reference_seed: the same object, other random numbers.
    test::Built free = test::build(window_scene(""));
    RenderOptions ro;
    free.scene.seed = reference_seed(a.scene, ro);
    ASSERT_NE(free.scene.seed, a.scene.seed);
    const SceneRun f = run(free, nullptr);
    const auto& mx = f.features.channel("MeanX");
    const auto& my = f.features.channel("MeanY");
    ASSERT_EQ(r.reference.size(), 2 * static_cast<size_t>(K));
    for (long k = 0; k < K; ++k) {
        EXPECT_TRUE(same(r.reference[2 * static_cast<size_t>(k)], mx[static_cast<size_t>(k)])) << k;
        EXPECT_TRUE(same(r.reference[2 * static_cast<size_t>(k) + 1], my[static_cast<size_t>(k)])) << k;
    }
    // So the deflection map is noisy where no path met the bubble: two independent estimates of
    // the same mean differ (a 0.02 NA bundle spreads over 2 to 3 display pixels at 30 mm, and 8
    // samples rarely split the same way twice). Rendered with the scene's own random numbers, every
    // such pixel would be its own reference and its deflection exactly 0.
    std::vector<char> met(static_cast<size_t>(K), 0);
    for (const DefectPaths& e : r.render.defect_paths) met[static_cast<size_t>(e.pixel)] = 1;
    long clear = 0, nonzero = 0;
    const auto& d = r.features.channel("Deflection");
    for (long k = 0; k < K; ++k) {
        if (met[static_cast<size_t>(k)] || !(d[static_cast<size_t>(k)] == d[static_cast<size_t>(k)])) continue;
        ++clear;
        nonzero += d[static_cast<size_t>(k)] != 0.0f;
    }
    ASSERT_GT(clear, K / 2);
    EXPECT_GT(nonzero, clear / 2) << nonzero << " of " << clear << " pixels away from the bubble";
}

TEST(Reference, BitIdenticalForAnyThreadCount) {
    const test::Built a = test::build(window_scene(kBubbleA));
    expect_same_reference(run(a, nullptr, 1), run(a, nullptr, 2));
}

TEST(ReferenceCache, ScenesOfOneObjectShareOneReferenceAndChangeNothing) {
    const test::Built free = test::build(window_scene("")), a = test::build(window_scene(kBubbleA)),
                      b = test::build(window_scene(kBubbleB));
    const SceneRun a_alone = run(a, nullptr), b_alone = run(b, nullptr), free_alone = run(free, nullptr);
    ReferenceCache cache;
    const SceneRun free_shared = run(free, &cache), a_shared = run(a, &cache), b_shared = run(b, &cache);
    expect_same_reference(free_alone, free_shared);
    expect_same_reference(a_alone, a_shared);
    expect_same_reference(b_alone, b_shared);
    // The first scene renders the reference; the others find it.
    EXPECT_EQ(free_shared.reference_pixels, 24 * 24);
    EXPECT_EQ(free_shared.reference_reused, 0);
    for (const SceneRun* s : {&a_shared, &b_shared}) {
        EXPECT_EQ(s->reference_pixels, 0);
        EXPECT_EQ(s->reference_reused, 24 * 24);
    }
    EXPECT_EQ(cache.reused(), 2);
}

TEST(ReferenceCache, AnotherSeedOrObjectSharesNothing) {
    ReferenceCache cache;
    run(test::build(window_scene("")), &cache);
    for (const std::string& yaml : {window_scene(kBubbleA, 4), window_scene(kBubbleA, 3, 1.6)}) {
        const test::Built b = test::build(yaml);
        const SceneRun alone = run(b, nullptr), shared = run(b, &cache);
        EXPECT_EQ(shared.reference_reused, 0);
        EXPECT_EQ(shared.reference_pixels, alone.reference_pixels);
        expect_same_reference(alone, shared);
    }
}

// A dataset's samples: scenes of one object with seeds of their own and one reference_seed share
// one reference, the same as the defect-free object rendered with the reference seed derived from
// that reference_seed, found in the cache by every scene after the first. Without reference_seed
// the seeds give two references.
TEST(Reference, ScenesOfOneObjectWithOneReferenceSeedShareItWhateverTheirSeeds) {
    const test::Built a = test::build(window_scene(kBubbleA, 3) + "reference_seed: 11\n");
    const test::Built b = test::build(window_scene(kBubbleB, 4) + "reference_seed: 11\n");
    const SceneRun ra = run(a, nullptr), rb = run(b, nullptr);
    ASSERT_EQ(ra.reference.size(), rb.reference.size());
    for (size_t i = 0; i < ra.reference.size(); ++i) EXPECT_TRUE(same(ra.reference[i], rb.reference[i])) << i;
    // That reference is the defect-free object's MeanX, MeanY rendered with seed
    // mix_seed(11, kReferenceStream).
    test::Built free = test::build(window_scene(""));
    free.scene.seed = reference_seed(a.scene, RenderOptions{});
    EXPECT_EQ(free.scene.seed, mix_seed(11, kReferenceStream));
    const SceneRun f = run(free, nullptr);
    for (size_t k = 0; k < ra.reference.size() / 2; ++k) {
        EXPECT_TRUE(same(ra.reference[2 * k], f.features.channel("MeanX")[k])) << k;
        EXPECT_TRUE(same(ra.reference[2 * k + 1], f.features.channel("MeanY")[k])) << k;
    }
    ReferenceCache cache;
    run(a, &cache);
    const SceneRun shared = run(b, &cache);
    EXPECT_EQ(shared.reference_reused, 24 * 24);
    expect_same_reference(rb, shared);
    // Seeds 3 and 4 without reference_seed: two independent references.
    const SceneRun a3 = run(test::build(window_scene(kBubbleA, 3)), nullptr), b4 = run(test::build(window_scene(kBubbleB, 4)), nullptr);
    long differ = 0;
    for (size_t i = 0; i < a3.reference.size(); ++i) differ += !same(a3.reference[i], b4.reference[i]);
    EXPECT_GT(differ, static_cast<long>(a3.reference.size() / 4));
}
