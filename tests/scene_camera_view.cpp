// What the camera sees of the object (scene/CameraView.h) and the loader's warnings built on it
// (docs/scene-format.md, "Warnings"): an object smaller than one camera pixel, a field that sees a
// sliver of the object. Each warning is one line, located at the key it blames, naming the sizes;
// no shipped scene warns.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "scene/CameraView.h"
#include "scene/SceneLoader.h"
#include "tests/BuildPaths.h"

namespace ltm {
namespace {

// The part of the disc rho <= a inside the rectangle |x| <= w, |y| <= h, by quadrature independent
// of CameraView's closed form: with x = a sin(t), the area is
//   4 a int_0^T min(h, a cos t) cos t dt,  T = asin(min(w / a, 1)),
// whose integrand is smooth on either side of the kink a cos t = h; composite Simpson on each side
// (2000 panels of a smooth integrand bounded with its derivatives by a^2: error below 1e-12 a^2).
double disc_area_in_rectangle(double a, double w, double h) {
    auto f = [&](double t) { return std::min(h, a * std::cos(t)) * std::cos(t); };
    auto simpson = [&](double lo, double hi) {
        const int n = 2000;
        const double step = (hi - lo) / n;
        double s = f(lo) + f(hi);
        for (int i = 1; i < n; ++i) s += f(lo + i * step) * (i % 2 ? 4 : 2);
        return s * step / 3;
    };
    const double T = std::asin(std::min(w / a, 1.0));
    const double kink = h < a ? std::acos(h / a) : T;
    return 4 * a * (kink < T ? simpson(0, kink) + simpson(kink, T) : simpson(0, T));
}

ObjectDesc lens_of_diameter(double diameter) {
    ObjectDesc o;
    o.lens = LensSpec{50, -50, 6, diameter, 1.5168};
    return o;
}

CameraDesc camera(double width, double height, int columns, int rows) {
    CameraDesc c;
    c.size = {width, height};
    c.resolution = {columns, rows};
    return c;
}

TEST(CameraView, SeenFractionMatchesQuadrature) {
    const double a = 12.5;
    // Inside the disc, across it, both sides clipping it, corners inside and outside, a thin strip.
    for (const auto& [W, H] : std::vector<std::pair<double, double>>{
             {5, 5}, {25, 25}, {100, 100}, {30, 10}, {10, 30}, {22, 22}, {24, 8}, {25, 0.025}, {1e-3, 40}}) {
        const double expected = disc_area_in_rectangle(a, 0.5 * W, 0.5 * H) / (kPi * a * a);
        EXPECT_NEAR(camera_view(lens_of_diameter(2 * a), camera(W, H, 10, 10)).seen_fraction, expected, 1e-12)
            << W << " x " << H;
    }
}

TEST(CameraView, PixelsAndSizes) {
    // The default camera (25 mm over 100 pixels: 0.25 mm footprints) and the default lens in
    // metres (diameter 0.025): pi 0.0125^2 / 0.25^2 = 0.00785 of a footprint.
    const CameraView v = camera_view(lens_of_diameter(0.025), camera(25, 25, 100, 100));
    EXPECT_EQ(v.object_diameter, 0.025);
    EXPECT_EQ(v.pixel_width, 0.25);
    EXPECT_EQ(v.pixel_height, 0.25);
    EXPECT_NEAR(v.object_in_pixels, kPi * 0.0125 * 0.0125 / 0.0625, 1e-15);
    EXPECT_EQ(v.seen_fraction, 1.0);
    // A ball's extent is its diameter 2 R.
    ObjectDesc ball;
    ball.type = ObjectType::Sphere;
    ball.lens = ball_spec(5, 1.5);
    EXPECT_EQ(camera_view(ball, camera(25, 25, 100, 100)).object_diameter, 10.0);
    // No product of lengths is formed: extreme but positive sizes give finite ratios.
    const CameraView tiny = camera_view(lens_of_diameter(1e-200), camera(1e200, 1e200, 1, 1));
    EXPECT_EQ(tiny.object_in_pixels, 0.0);
    EXPECT_GT(camera_view(lens_of_diameter(1e200), camera(1e-200, 1e-200, 1, 1)).object_in_pixels, 1.0);
}

// The first case: scenes/default.yaml with every length of the object in metres.
const std::string kMetres =
    "object: {type: lens, r1: 0.05, r2: -0.05, center_thickness: 0.006, diameter: 0.025, ior: 1.5168}\n"
    "defects:\n"
    "  - {type: bubble, center: [0.0, 0.0, 0.0], radius: 0.0001}\n"
    "camera: {resolution: [100, 100], size: [25.0, 25.0]}\n";

TEST(SceneWarnings, ObjectSmallerThanAPixel) {
    const Scene s = parse_scene(kMetres, "scene.yaml");
    ASSERT_EQ(s.warnings.size(), 1u);
    EXPECT_EQ(s.warnings[0],
              "scene.yaml:1:78: warning: object.diameter: the object (diameter 0.025 mm) is smaller than one camera "
              "pixel (0.25 x 0.25 mm: camera.size over camera.resolution), 0.00785 of its area; lengths are in mm: "
              "were the object's given in metres?");
    // A pixel's area is the threshold: a 0.28 mm lens (0.985 of a 0.25 mm footprint) warns, a 0.29 mm
    // one (1.06) does not.
    EXPECT_EQ(parse_scene("object: {type: window, thickness: 0.1, diameter: 0.28, ior: 1.5}\n", "w.yaml").warnings.size(), 1u);
    EXPECT_TRUE(parse_scene("object: {type: window, thickness: 0.1, diameter: 0.29, ior: 1.5}\n", "w.yaml").warnings.empty());
    // A sphere is blamed at its radius.
    const Scene ball = parse_scene("object: {type: sphere, radius: 0.01, ior: 1.5}\n", "b.yaml");
    ASSERT_EQ(ball.warnings.size(), 1u);
    EXPECT_EQ(ball.warnings[0].rfind("b.yaml:1:32: warning: object.radius: the object (diameter 0.02 mm)", 0), 0u)
        << ball.warnings[0];
}

TEST(SceneWarnings, FieldSeesASliver) {
    // camera.size in metres for the 25 mm lens: 4 (0.0125 / 12.5)^2 / pi = 1.27e-6 of its disc.
    const std::string lens = "object: {type: lens, r1: 50, r2: -50, center_thickness: 6, diameter: 25, ior: 1.5168}\n";
    const Scene s = parse_scene(lens + "camera:\n  size: [0.025, 0.025]\n", "scene.yaml");
    ASSERT_EQ(s.warnings.size(), 1u);
    EXPECT_EQ(s.warnings[0],
              "scene.yaml:3:9: warning: camera.size: the camera's field (0.025 x 0.025 mm, centred on the axis) sees "
              "1.27e-06 of the object's extent (diameter 25 mm); lengths are in mm: was camera.size given in metres?");
    // Without camera.size in the file the object is blamed (the default 25 mm field on a lens in
    // micrometres, 25000 mm: it sees 1.27e-6 of it).
    const Scene big = parse_scene("object: {type: window, thickness: 6000, diameter: 25000, ior: 1.5}\n"
                                  "display: {z: 4000}\n",
                                  "big.yaml");
    ASSERT_EQ(big.warnings.size(), 1u);
    EXPECT_EQ(big.warnings[0].rfind("big.yaml:1:51: warning: object.diameter: the camera's field (25 x 25 mm", 0), 0u)
        << big.warnings[0];
    EXPECT_NE(big.warnings[0].find("were the object's given in micrometres?"), std::string::npos) << big.warnings[0];
    // A line-scan field across the whole lens (25 x 0.025 mm: 1.27e-3 of it) is no sliver.
    EXPECT_TRUE(parse_scene(lens + "camera: {size: [25, 0.025], resolution: [1000, 1]}\n", "scene.yaml").warnings.empty());
}

TEST(SceneWarnings, InlineSceneKeysCarryTheirPrefix) {
    const YAML::Node root = YAML::Load("scene: {object: {type: lens, r1: 0.05, r2: -0.05, center_thickness: 0.006, "
                                       "diameter: 0.025, ior: 1.5}}\n");
    const Scene s = parse_scene_node(root["scene"], "spec.yaml", "scene");
    ASSERT_EQ(s.warnings.size(), 1u);
    EXPECT_EQ(s.warnings[0].rfind("spec.yaml:1:86: warning: scene.object.diameter: ", 0), 0u) << s.warnings[0];
}

TEST(SceneWarnings, NoShippedSceneWarns) {
    int count = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(ltm::test::source_dir() + "/scenes")) {
        if (entry.path().extension() != ".yaml") continue;
        if (entry.path().filename() == "experiment.yaml") continue;         // an experiment's list of scenes
        if (entry.path().parent_path().filename() == "datasets") continue;  // dataset specs
        ++count;
        const Scene s = load_scene(entry.path().string());
        EXPECT_TRUE(s.warnings.empty()) << entry.path() << ": " << (s.warnings.empty() ? "" : s.warnings[0]);
    }
    EXPECT_GE(count, 26);
}

}  // namespace
}  // namespace ltm
