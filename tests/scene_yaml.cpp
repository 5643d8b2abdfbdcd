// Scenes written as scene files (scene/SceneYaml.h) are the exact inverse of the loader: for every
// shipped scene and for hand-built scenes that set every field to awkward values,
//   parse(write(s)) == s        in every field, doubles bit for bit (-0 is not 0),
//   write(parse(write(s))) == write(s)   as text,
//   scene_to_json of both is the same (what run.json records).
// A dataset sample's scene.yaml is rendered again by `ltmsim render`, so nothing less than bit
// equality would do.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

#include "io/Json.h"
#include "scene/SceneJson.h"
#include "scene/SceneLoader.h"
#include "scene/SceneYaml.h"
#include "tests/BuildPaths.h"

namespace ltm {
namespace {

const std::string kSourceDir = ltm::test::source_dir();

// ---------------------------------------------------------------------------------------------
// Field-by-field comparison. Every field of Scene and of the structs it holds is listed here; a
// field added to them must be added here too.

class Differences {
public:
    void bits(const std::string& what, double a, double b) {
        std::uint64_t x = 0, y = 0;
        std::memcpy(&x, &a, sizeof x);
        std::memcpy(&y, &b, sizeof y);
        if (x != y) out_ += fmt::format("{}: {} != {}\n", what, a, b);
    }
    void vec(const std::string& what, const Vec3& a, const Vec3& b) {
        bits(what + ".x", a.x, b.x);
        bits(what + ".y", a.y, b.y);
        bits(what + ".z", a.z, b.z);
    }
    void mat(const std::string& what, const Mat3& a, const Mat3& b) {
        for (std::size_t i = 0; i < 9; ++i) bits(fmt::format("{}[{}]", what, i), a.m[i], b.m[i]);
    }
    template <class T>
    void same(const std::string& what, const T& a, const T& b) {
        if (!(a == b)) out_ += what + " differs\n";
    }
    const std::string& text() const { return out_; }

private:
    std::string out_;
};

void compare(Differences& d, const std::string& p, const Defect& a, const Defect& b) {
    d.same(p + ".type", a.type, b.type);
    d.vec(p + ".center", a.center, b.center);
    d.vec(p + ".semi_axes", a.semi_axes, b.semi_axes);
    d.mat(p + ".frame", a.frame, b.frame);
    d.same(p + ".rotation_given", a.rotation_given, b.rotation_given);
    d.vec(p + ".rotation_deg", a.rotation_deg, b.rotation_deg);
    d.same(p + ".surface_breaking", a.surface_breaking, b.surface_breaking);
    d.bits(p + ".delta_n", a.delta_n, b.delta_n);
    d.same(p + ".index_profile", a.index_profile, b.index_profile);
    d.same(p + ".side", a.side, b.side);
    d.same(p + ".arc", a.arc, b.arc);
    d.vec(p + ".start", a.start, b.start);
    d.vec(p + ".end", a.end, b.end);
    d.same(p + ".start_has_z", a.start_has_z, b.start_has_z);
    d.same(p + ".end_has_z", a.end_has_z, b.end_has_z);
    d.vec(p + ".arc_center", a.arc_center, b.arc_center);
    d.same(p + ".arc_center_has_z", a.arc_center_has_z, b.arc_center_has_z);
    d.bits(p + ".arc_radius", a.arc_radius, b.arc_radius);
    d.bits(p + ".start_angle", a.start_angle, b.start_angle);
    d.bits(p + ".end_angle", a.end_angle, b.end_angle);
    d.bits(p + ".width", a.width, b.width);
    d.bits(p + ".depth", a.depth, b.depth);
    d.same(p + ".profile", a.profile, b.profile);
}

// "" when the scenes are equal in every field, else one line per differing field.
std::string differences(const Scene& a, const Scene& b) {
    Differences d;
    d.same("source", a.source, b.source);
    d.same("object.type", a.object.type, b.object.type);
    const LensSpec &la = a.object.lens, &lb = b.object.lens;
    d.bits("object.lens.r1", la.r1, lb.r1);
    d.bits("object.lens.r2", la.r2, lb.r2);
    d.bits("object.lens.center_thickness", la.center_thickness, lb.center_thickness);
    d.bits("object.lens.diameter", la.diameter, lb.diameter);
    d.bits("object.lens.ior", la.ior, lb.ior);
    d.same("object.lens.ball", la.ball, lb.ball);
    d.same("object.rim", a.object.rim, b.object.rim);
    d.bits("object.absorption", a.object.absorption, b.object.absorption);
    const IndexField &fa = a.object.index_field, &fb = b.object.index_field;
    d.same("object.index_field.type", fa.type, fb.type);
    d.bits("object.index_field.ior", fa.ior, fb.ior);
    d.vec("object.index_field.gradient", fa.gradient, fb.gradient);
    d.bits("object.index_field.g", fa.g, fb.g);
    d.mat("object.index_field.hessian", fa.hessian, fb.hessian);
    d.same("defects.size", a.defects.size(), b.defects.size());
    for (std::size_t i = 0; i < a.defects.size() && i < b.defects.size(); ++i)
        compare(d, fmt::format("defects[{}]", i), a.defects[i], b.defects[i]);
    d.same("camera.resolution", a.camera.resolution, b.camera.resolution);
    d.bits("camera.size[0]", a.camera.size[0], b.camera.size[0]);
    d.bits("camera.size[1]", a.camera.size[1], b.camera.size[1]);
    d.bits("camera.numerical_aperture", a.camera.numerical_aperture, b.camera.numerical_aperture);
    d.same("camera.samples_per_pixel", a.camera.samples_per_pixel, b.camera.samples_per_pixel);
    d.bits("camera.focus_z", a.camera.focus_z, b.camera.focus_z);
    d.same("display.resolution", a.display.resolution, b.display.resolution);
    d.bits("display.size[0]", a.display.size[0], b.display.size[0]);
    d.bits("display.size[1]", a.display.size[1], b.display.size[1]);
    d.bits("display.z", a.display.z, b.display.z);
    d.bits("mesh.chord_tolerance", a.mesh.chord_tolerance, b.mesh.chord_tolerance);
    d.bits("mesh.defect_relative_tolerance", a.mesh.defect_relative_tolerance, b.mesh.defect_relative_tolerance);
    d.same("mesh.always_boolean", a.mesh.always_boolean, b.mesh.always_boolean);
    d.bits("mesh.index_tolerance", a.mesh.index_tolerance, b.mesh.index_tolerance);
    d.same("tracing.estimator", a.tracing.estimator, b.tracing.estimator);
    // A sample scene's split_depth means nothing and is not written (scene/SceneYaml.cpp).
    if (a.tracing.estimator == Estimator::Split) d.same("tracing.split_depth", a.tracing.split_depth, b.tracing.split_depth);
    d.same("seed", a.seed, b.seed);
    d.same("reference_seed given", a.reference_seed.has_value(), b.reference_seed.has_value());
    if (a.reference_seed && b.reference_seed) d.same("reference_seed", *a.reference_seed, *b.reference_seed);
    return d.text();
}

// The three properties of the file comment, for one scene.
void expect_round_trip(const Scene& s, const std::string& label) {
    const std::string text = scene_to_yaml(s);
    Scene back;
    try {
        back = parse_scene(text, s.source);
    } catch (const SceneError& e) {
        ADD_FAILURE() << label << ": the written scene does not load: " << e.what() << "\n" << text;
        return;
    }
    EXPECT_EQ(differences(s, back), "") << label << "\n" << text;
    EXPECT_EQ(scene_to_yaml(back), text) << label;
    EXPECT_EQ(scene_to_json(back), scene_to_json(s)) << label;
}

// ---------------------------------------------------------------------------------------------
// Shipped scenes

TEST(SceneYaml, EveryShippedSceneRoundTrips) {
    int count = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(kSourceDir + "/scenes")) {
        if (entry.path().extension() != ".yaml") continue;
        if (entry.path().filename() == "experiment.yaml") continue;  // an experiment's list of scenes
        if (entry.path().parent_path().filename() == "datasets") continue;  // dataset specs (docs/dataset.md)
        ++count;
        expect_round_trip(load_scene(entry.path().string()), entry.path().string());
    }
    EXPECT_GE(count, 26);  // default.yaml, 21 examples, 4 paper scenes
}

// ---------------------------------------------------------------------------------------------
// Hand-built scenes: every field, awkward values

const std::string kLens =
    "object: {type: lens, r1: 50, r2: -50, center_thickness: 6, diameter: 25, ior: 1.5168}\n";

void set_ior(Scene& s, double ior) { s.object.lens.ior = s.object.index_field.ior = ior; }

Defect ellipsoid(DefectType type, const Vec3& center, const Vec3& semi_axes) {
    Defect d;
    d.type = type;
    d.center = center;
    d.semi_axes = semi_axes;
    return d;
}

TEST(SceneYaml, EveryFieldWithAwkwardValues) {
    Scene s = parse_scene(kLens, "awkward.yaml");
    s.object.lens.r1 = 50.0 + 1.0 / 3.0;
    s.object.lens.r2 = -50.0 - 1.0 / 7.0;
    s.object.lens.center_thickness = 6.0 + std::ldexp(1.0, -40);
    s.object.lens.diameter = 25.0 - 1.0 / 3.0;
    set_ior(s, 1.5168 + std::ldexp(1.0, -45));
    s.object.rim = RimFinish::Absorbing;
    s.object.absorption = 1.0 / 3000.0;
    const double front = -0.5 * s.object.lens.center_thickness, back = -front;

    // Bubbles: rotated ellipsoid (angles of no short decimal), a sphere given as equal semi_axes
    // (written as radius), a rotated sphere (semi_axes with rotation), a pit through the front.
    Defect b = ellipsoid(DefectType::Bubble, {1.0 / 3.0, -2.0 / 3.0, 0.1}, {0.1 / 3.0, 0.2 / 7.0, 0.05});
    b.set_rotation_deg({1.0 / 3.0, -200.0 / 7.0, 1e-7});
    s.defects.push_back(b);
    s.defects.push_back(ellipsoid(DefectType::Bubble, {-1.0 / 3.0, 0.25, -0.5}, {0.1, 0.1, 0.1}));
    Defect rs = ellipsoid(DefectType::Bubble, {0.7, 0.7, 0.7}, {0.06, 0.06, 0.06});
    rs.set_rotation_deg({10, 20, 30});
    s.defects.push_back(rs);
    Defect pit = ellipsoid(DefectType::Bubble, {-1.0, -1.0 / 9.0, front + 1.0 / 30.0}, {0.2, 0.1, 0.15});
    pit.surface_breaking = true;
    s.defects.push_back(pit);
    // A particle with -0 and an angle one ulp below 360.
    Defect p = ellipsoid(DefectType::Particle, {2.0, -2.0 / 7.0, 1.0 / 3.0}, {0.15, 0.05, 0.05});
    p.set_rotation_deg({-0.0, 90.0, std::nextafter(360.0, 0.0)});
    s.defects.push_back(p);
    // Inhomogeneities: smooth sphere with a negative delta_n, uniform rotated ellipsoid.
    Defect smooth = ellipsoid(DefectType::Inhomogeneity, {6.0, 6.0 + 1.0 / 3.0, 0.0}, {0.5, 0.5, 0.5});
    smooth.delta_n = -1.0 / 300.0;
    s.defects.push_back(smooth);
    Defect uniform = ellipsoid(DefectType::Inhomogeneity, {-6.0, 5.0, 1.0 / 7.0}, {0.3, 0.2, 0.1});
    uniform.set_rotation_deg({45.0 / 7.0, 0.0, -1.0 / 3.0});
    uniform.delta_n = 0.02 / 3.0;
    uniform.index_profile = IndexProfile::Uniform;
    s.defects.push_back(uniform);
    // Scratches: straight V on the front with z on its start (the face's own z, within 1 % of
    // the depth), straight U on the back without z, an arc U on the back with z on its centre.
    Defect sv;
    sv.type = DefectType::Scratch;
    sv.side = 0;
    sv.start = {0.0, 0.0, front + 1e-6};
    sv.start_has_z = true;
    sv.end = {2.0 / 3.0, 1.0 / 7.0, 0.0};
    sv.width = 0.05 / 3.0;
    sv.depth = 0.02 + 1.0 / 7e3;
    s.defects.push_back(sv);
    Defect su = sv;
    su.side = 1;
    su.start = {-3.0, -1.0 / 3.0, 0.0};
    su.start_has_z = false;
    su.end = {-4.0, -2.0, 0.0};
    su.profile = ScratchProfile::U;
    s.defects.push_back(su);
    Defect arc;
    arc.type = DefectType::Scratch;
    arc.side = 1;
    arc.arc = true;
    arc.arc_center = {0.0, 0.0, back};
    arc.arc_center_has_z = true;
    arc.arc_radius = 6.0 + 1.0 / 3.0;
    arc.start_angle = 1.0 / 3.0;
    arc.end_angle = 90.0 + 1.0 / 7.0;
    arc.width = 0.08;
    arc.depth = 0.03;
    arc.profile = ScratchProfile::U;
    s.defects.push_back(arc);

    s.camera.resolution = {7, 3};
    s.camera.size = {25.0 / 3.0, 0.1 + 0.2};
    s.camera.numerical_aperture = 0.1 + 0.2;
    s.camera.samples_per_pixel = 3;
    s.camera.focus_z = -0.0;
    s.display.resolution = {1, 999};
    s.display.size = {1e300, std::numeric_limits<double>::denorm_min()};
    s.display.z = 60.0 + 1.0 / 3.0;
    s.mesh.chord_tolerance = 1e-3 / 3.0;
    s.mesh.defect_relative_tolerance = 0.5;
    s.mesh.always_boolean = true;
    s.mesh.index_tolerance = 0.1 / 3.0;
    s.seed = std::numeric_limits<std::uint64_t>::max();
    expect_round_trip(s, "awkward");
    s.seed = std::numeric_limits<std::uint64_t>::max() - 1;
    expect_round_trip(s, "awkward, seed 2^64-2");
    s.reference_seed = std::numeric_limits<std::uint64_t>::max();
    expect_round_trip(s, "awkward, reference_seed 2^64-1");
    s.reference_seed = 0;
    expect_round_trip(s, "awkward, reference_seed 0");
}

TEST(SceneYaml, IndexFieldsOfEveryTypeOnEveryObject) {
    // linear_n2 on a lens
    Scene lens = parse_scene(kLens, "linear_n2.yaml");
    lens.object.index_field.type = IndexFieldType::LinearN2;
    lens.object.index_field.gradient = {1e-3 / 3.0, -1e-4 / 7.0, 2e-3};
    lens.defects.push_back(ellipsoid(DefectType::Bubble, {0.1, 0.2, 1.0 / 3.0}, {0.1, 0.1, 0.1}));
    expect_round_trip(lens, "linear_n2");
    // linear_n on the same lens
    lens.object.index_field.type = IndexFieldType::LinearN;
    lens.object.index_field.gradient = {0.0, 1e-3 / 3.0, 0.0};
    expect_round_trip(lens, "linear_n");
    // quadratic_n2: a symmetric hessian of no short decimals
    lens.object.index_field.type = IndexFieldType::QuadraticN2;
    lens.object.index_field.gradient = {0.0, 0.0, 0.002 / 3.0};
    Mat3& h = lens.object.index_field.hessian;
    h = Mat3::zero();
    h(0, 0) = -8e-4 / 3.0;
    h(1, 1) = -4e-4;
    h(2, 2) = 1e-6 / 3.0;
    h(0, 1) = h(1, 0) = 1e-5 / 7.0;
    h(1, 2) = h(2, 1) = -0.0;
    expect_round_trip(lens, "quadratic_n2");

    // radial_n2 on a window with an absorbing rim and a rotated particle
    Scene window =
        parse_scene("object: {type: window, thickness: 5, diameter: 25, ior: 1.6, rim: absorbing}\n", "radial.yaml");
    window.object.lens.center_thickness = 5.0 + 1.0 / 3.0;
    window.object.index_field.type = IndexFieldType::RadialN2;
    window.object.index_field.g = 0.01 / 3.0;
    Defect p = ellipsoid(DefectType::Particle, {1.0, 1.0, 0.0}, {0.2, 0.1, 0.05});
    p.set_rotation_deg({30.0 / 7.0, 0.0, 0.0});
    window.defects.push_back(p);
    expect_round_trip(window, "radial_n2 window");

    // spherical_n2 on a ball (a Luneburg lens, just inside n >= 1)
    Scene ball = parse_scene("object: {type: sphere, radius: 5, ior: 1.4142135623730951}\n", "ball.yaml");
    const double R = 5.0 + 1.0 / 3.0;
    ball.object.lens = ball_spec(R, std::sqrt(2.0));
    ball.object.index_field.ior = ball.object.lens.ior;
    ball.object.index_field.type = IndexFieldType::SphericalN2;
    ball.object.index_field.g = 0.99 / (R * std::sqrt(2.0));
    ball.object.absorption = 0.01 / 7.0;
    ball.defects.push_back(ellipsoid(DefectType::Bubble, {0.0, 1.0 / 3.0, -1.0}, {0.25, 0.25, 0.25}));
    expect_round_trip(ball, "spherical_n2 ball");
    // and the same ball homogeneous
    ball.object.index_field = IndexField{};
    ball.object.index_field.ior = ball.object.lens.ior;
    expect_round_trip(ball, "homogeneous ball");
}

// Seeded random ellipsoids (centres, semi-axes and angles of 53 random bits) and camera values.
TEST(SceneYaml, RandomEllipsoidsRoundTrip) {
    std::mt19937_64 rng(20240611);
    auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * std::ldexp(static_cast<double>(rng() >> 11), -53); };
    const Scene base = parse_scene(kLens, "random.yaml");
    for (int i = 0; i < 300; ++i) {
        Scene s = base;
        const DefectType type = i % 3 == 0 ? DefectType::Bubble : (i % 3 == 1 ? DefectType::Particle : DefectType::Inhomogeneity);
        Defect d = ellipsoid(type, {uniform(-2, 2), uniform(-2, 2), uniform(-1, 1)},
                             {uniform(0.01, 0.3), uniform(0.01, 0.3), uniform(0.01, 0.3)});
        if (i % 4 != 0) d.set_rotation_deg({uniform(-360, 360), uniform(-360, 360), uniform(-360, 360)});
        if (type == DefectType::Inhomogeneity) d.delta_n = uniform(-0.05, 0.05);
        s.defects.push_back(d);
        s.camera.size = {uniform(1, 30), uniform(1, 30)};
        s.camera.numerical_aperture = uniform(1e-4, 0.5);
        s.camera.focus_z = uniform(-3, 3);
        s.seed = rng();
        expect_round_trip(s, fmt::format("random scene {}", i));
        if (HasFailure()) break;
    }
}

// ---------------------------------------------------------------------------------------------
// The text itself

TEST(SceneYaml, WritesEveryKeyOfAMinimalScene) {
    const Scene s = parse_scene(kLens + "defects: [{type: bubble, center: [0, 0, 0], radius: 0.1}]\n", "min.yaml");
    EXPECT_EQ(scene_to_yaml(s),
              "# A scene written by ltmsim: every key resolved, defaults included (docs/scene-format.md).\n"
              "object:\n"
              "  type: lens\n"
              "  r1: 50\n"
              "  r2: -50\n"
              "  center_thickness: 6\n"
              "  diameter: 25\n"
              "  ior: 1.5168\n"
              "  rim: polished\n"
              "  absorption: 0\n"
              "defects:\n"
              "  - type: bubble\n"
              "    center: [0, 0, 0]\n"
              "    radius: 0.1\n"
              "    surface_breaking: false\n"
              "camera:\n"
              "  resolution: [100, 100]\n"
              "  size: [25, 25]\n"
              "  numerical_aperture: 0.01\n"
              "  samples_per_pixel: 64\n"
              "  focus_z: 0\n"
              "display:\n"
              "  resolution: [500, 500]\n"
              "  size: [100, 100]\n"
              "  z: 60\n"
              "mesh:\n"
              "  chord_tolerance: 0.001\n"
              "  defect_relative_tolerance: 0.01\n"
              "  always_boolean: false\n"
              "  index_tolerance: 0.0001\n"
              "seed: 1\n");
}

TEST(SceneYaml, TheSplitEstimatorRoundTripsAndTheSampleOneWritesNoSection) {
    for (int depth : {0, 1, kDefaultSplitDepth, kMaxSplitDepth}) {
        Scene s = parse_scene(kLens, "split.yaml");
        s.tracing.estimator = Estimator::Split;
        s.tracing.split_depth = depth;
        expect_round_trip(s, fmt::format("split depth {}", depth));
        EXPECT_NE(scene_to_yaml(s).find(fmt::format("tracing:\n  estimator: split\n  split_depth: {}\nseed: 1\n", depth)),
                  std::string::npos);
    }
    // The default estimator keeps the files written before the section existed byte for byte.
    const Scene sample = parse_scene(kLens + "tracing: {estimator: sample}\n", "sample.yaml");
    EXPECT_EQ(sample.tracing.estimator, Estimator::Sample);
    EXPECT_EQ(scene_to_yaml(sample).find("tracing"), std::string::npos);
    EXPECT_EQ(scene_to_yaml(sample), scene_to_yaml(parse_scene(kLens, "sample.yaml")));
}

TEST(SceneYaml, FormatsOfTheOtherObjectsAndDefects) {
    const Scene s = parse_scene(
        "object: {type: window, thickness: 5, diameter: 25, ior: 1.5}\n"
        "defects:\n"
        "  - {type: particle, center: [0, 0, 0], semi_axes: [0.2, 0.1, 0.1], rotation: [0, 0, 45]}\n"
        "  - {type: inhomogeneity, center: [3, 0, 0], radius: 0.5, delta_n: -0.01, profile: uniform}\n"
        "  - {type: scratch, surface: back, width: 0.05, depth: 0.02, start: [-5, -5, 2.5], end: [-4, -5]}\n"
        "  - {type: scratch, surface: front, width: 0.05, depth: 0.02, profile: U,\n"
        "     arc: {center: [5, 5], radius: 2, start_angle: -10, end_angle: 200}}\n",
        "formats.yaml");
    const std::string text = scene_to_yaml(s);
    const std::string expected_object_and_defects =
        "object:\n"
        "  type: window\n"
        "  thickness: 5\n"
        "  diameter: 25\n"
        "  ior: 1.5\n"
        "  rim: polished\n"
        "  absorption: 0\n"
        "defects:\n"
        "  - type: particle\n"
        "    center: [0, 0, 0]\n"
        "    semi_axes: [0.2, 0.1, 0.1]\n"
        "    rotation: [0, 0, 45]\n"
        "  - type: inhomogeneity\n"
        "    center: [3, 0, 0]\n"
        "    radius: 0.5\n"
        "    delta_n: -0.01\n"
        "    profile: uniform\n"
        "  - type: scratch\n"
        "    surface: back\n"
        "    width: 0.05\n"
        "    depth: 0.02\n"
        "    profile: V\n"
        "    start: [-5, -5, 2.5]\n"
        "    end: [-4, -5]\n"
        "  - type: scratch\n"
        "    surface: front\n"
        "    width: 0.05\n"
        "    depth: 0.02\n"
        "    profile: U\n"
        "    arc:\n"
        "      center: [5, 5]\n"
        "      radius: 2\n"
        "      start_angle: -10\n"
        "      end_angle: 200\n"
        "camera:\n";
    EXPECT_NE(text.find(expected_object_and_defects), std::string::npos) << text;
    const Scene ball = parse_scene("object: {type: sphere, radius: 5, ior: 1.5, index_field: {type: radial_n2, g: 0.01}}\n"
                                   "display: {z: 60}\n",
                                   "ball.yaml");
    EXPECT_NE(scene_to_yaml(ball).find("object:\n  type: sphere\n  radius: 5\n  ior: 1.5\n  absorption: 0\n"
                                       "  index_field:\n    type: radial_n2\n    g: 0.01\ndefects: []\ncamera:\n"),
              std::string::npos)
        << scene_to_yaml(ball);
    const Scene flat = parse_scene("object: {type: lens, r1: -inf, r2: -50, center_thickness: 6, diameter: 25, ior: 1.5}\n",
                                   "flat.yaml");
    EXPECT_NE(scene_to_yaml(flat).find("  r1: inf\n  r2: -50\n"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Scenes no file can express

TEST(SceneYaml, RefusesWhatNoFileCanExpress) {
    Scene s = parse_scene(kLens, "refuse.yaml");
    Defect d = ellipsoid(DefectType::Bubble, {0, 0, 0}, {0.2, 0.1, 0.1});
    d.frame = rotation_from_euler_deg({10, 20, 30});  // no angles recorded
    s.defects.push_back(d);
    EXPECT_THROW(scene_to_yaml(s), std::invalid_argument);
    s.defects.back().set_rotation_deg({10, 20, 30});
    EXPECT_NO_THROW(scene_to_yaml(s));
    s.defects.back().rotation_deg.z = 31;  // the angles no longer those of the frame
    EXPECT_THROW(scene_to_yaml(s), std::invalid_argument);
    s.defects.clear();

    s.object.lens.ior = 1.6;  // the index field still says 1.5168
    EXPECT_THROW(scene_to_yaml(s), std::invalid_argument);
    set_ior(s, 1.6);
    EXPECT_NO_THROW(scene_to_yaml(s));
    s.camera.focus_z = std::nan("");
    EXPECT_THROW(scene_to_yaml(s), std::invalid_argument);

    Scene ball = parse_scene("object: {type: sphere, radius: 5, ior: 1.5}\n", "ball.yaml");
    ball.object.rim = RimFinish::Absorbing;
    EXPECT_THROW(scene_to_yaml(ball), std::invalid_argument);
    ball.object.rim = RimFinish::Polished;
    ball.object.lens.diameter = 9;
    EXPECT_THROW(scene_to_yaml(ball), std::invalid_argument);
}

}  // namespace
}  // namespace ltm
