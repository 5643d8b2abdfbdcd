// The defect-free reference shared between scenes (study/ReferenceCache.h): it must never change
// a result. Scenes with the same object, camera, display and seed, run through one cache, give
// bit for bit the reference and the deflection images each gives alone, while the pixels a scene
// before them rendered (or a defect-free scene, every pixel) are not rendered again. Scenes whose
// key differs (another seed, another object) share nothing.
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
const std::string kBubbleB = "  - {type: bubble, center: [-1.5, 1.0, 0.5], radius: 0.6}\n";  // overlaps A's image

SceneRun run(const test::Built& b, ReferenceCache* cache) {
    SceneRunOptions o;
    o.representation = auto_representation(b.solid);
    o.threads = 2;
    o.reference_cache = cache;
    return run_scene(b.scene, b.solid, o, nullptr);
}

void expect_same_reference(const SceneRun& alone, const SceneRun& shared) {
    ASSERT_EQ(alone.reference.size(), shared.reference.size());
    for (size_t i = 0; i < alone.reference.size(); ++i) {
        // Bit for bit: NaN (an empty row) on both sides, or the same float.
        const float a = alone.reference[i], b = shared.reference[i];
        EXPECT_TRUE((a != a && b != b) || a == b) << "value " << i << ": " << a << " vs " << b;
    }
    for (const char* ch : {"DeflectionX", "DeflectionY", "Deflection"}) {
        const auto& a = alone.features.channel(ch);
        const auto& b = shared.features.channel(ch);
        for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE((a[i] != a[i] && b[i] != b[i]) || a[i] == b[i]) << ch << " " << i;
    }
}

}  // namespace

TEST(ReferenceCache, OverlappingDefectsShareTheirPixelsAndChangeNothing) {
    const test::Built a = test::build(window_scene(kBubbleA)), b = test::build(window_scene(kBubbleB));
    const SceneRun a_alone = run(a, nullptr), b_alone = run(b, nullptr);
    ASSERT_GT(a_alone.reference_pixels, 0);
    ReferenceCache cache;
    const SceneRun a_shared = run(a, &cache), b_shared = run(b, &cache);
    expect_same_reference(a_alone, a_shared);
    expect_same_reference(b_alone, b_shared);
    EXPECT_EQ(a_shared.reference_reused, 0);  // the first scene finds nothing
    EXPECT_EQ(a_shared.reference_pixels, a_alone.reference_pixels);
    // The second renders only what the first did not: together they cover its pixels, some reused.
    EXPECT_GT(b_shared.reference_reused, 0);
    EXPECT_EQ(b_shared.reference_pixels + b_shared.reference_reused, b_alone.reference_pixels);
    EXPECT_EQ(cache.reused(), b_shared.reference_reused);
}

TEST(ReferenceCache, ADefectFreeSceneIsEveryPixelsReference) {
    const test::Built free = test::build(window_scene("")), a = test::build(window_scene(kBubbleA));
    const SceneRun a_alone = run(a, nullptr);
    ReferenceCache cache;
    run(free, &cache);
    const SceneRun a_shared = run(a, &cache);
    expect_same_reference(a_alone, a_shared);
    EXPECT_EQ(a_shared.reference_pixels, 0);
    EXPECT_EQ(a_shared.reference_reused, a_alone.reference_pixels);
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
