// A scene file written by scene_to_yaml (scene/SceneYaml.h) renders the very same light transport
// matrix as the file it was loaded from: `ltmsim render` on both gives byte-identical ltm.npz
// files. This is what a dataset sample's scene.yaml promises. A matrix this coarse (float32, few
// samples) does not notice a one-ulp change of an angle, so this checks the pipeline end to end
// (a lost rotation or z, a key the writer forgot); tests/scene_yaml.cpp checks the scene itself,
// field by field and bit for bit.
//
// The scene is small (16 x 16 camera pixels, 8 samples each, 32 x 32 display pixels) and holds
// what a round trip could get wrong: a rotated ellipsoid with angles of no short decimal, a
// rotated particle, an arc scratch with its centre's z, a straight scratch, a -0 focus.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "scene/SceneLoader.h"
#include "scene/SceneYaml.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;

namespace {

const char* kScene =
    "object: {type: lens, r1: 50.333333333333336, r2: -50.142857142857146, center_thickness: 6.0,\n"
    "         diameter: 25.0, ior: 1.5168, rim: absorbing, absorption: 0.0003333333333333333}\n"
    "defects:\n"
    "  - {type: bubble, center: [0.3333333333333333, -0.6666666666666666, 0.1], semi_axes: [0.7, 0.4, 0.3],\n"
    "     rotation: [0.3333333333333333, -28.571428571428573, 1e-07]}\n"
    "  - {type: particle, center: [4.0, 2.0, 0.5], semi_axes: [0.6, 0.3, 0.2], rotation: [-0.0, 90, 359.99999999999994]}\n"
    "  - {type: scratch, surface: back, width: 0.2, depth: 0.05, profile: U,\n"
    "     arc: {center: [0, 0, 3.0], radius: 6.333333333333333, start_angle: 0.3333333333333333, end_angle: 90.14285714285714}}\n"
    "  - {type: scratch, surface: front, width: 0.15, depth: 0.04, start: [-6, -4], end: [-2, -7.5]}\n"
    "camera: {resolution: [16, 16], size: [26.0, 26.0], numerical_aperture: 0.05, samples_per_pixel: 8, focus_z: -0.0}\n"
    "display: {resolution: [32, 32], size: [80.0, 80.0], z: 60.333333333333336}\n"
    "seed: 18446744073709551615\n";

class SceneYamlRender : public ltm::test::TempDirTest {};

TEST_F(SceneYamlRender, TheWrittenFileRendersTheSameMatrix) {
    const fs::path original = write("original.yaml", kScene);
    const fs::path written = write("written.yaml", ltm::scene_to_yaml(ltm::load_scene(original.string())));
    for (const char* name : {"original", "written"}) {
        const ltm::test::Outcome r = ltm::test::ltmsim(
            "render '" + (dir / (std::string(name) + ".yaml")).string() + "' -o '" + (dir / name).string() + "' --threads 2",
            dir);
        ASSERT_EQ(r.status, 0) << name << ": " << r.err;
    }
    const std::string a = ltm::test::slurp(dir / "original" / "ltm.npz"), b = ltm::test::slurp(dir / "written" / "ltm.npz");
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << "ltm.npz of the written scene file differs from the original's (" << a.size() << " vs "
                        << b.size() << " bytes)\n"
                        << ltm::test::slurp(written);
}

}  // namespace
