// The strict scene loader (scene/SceneLoader.h, docs/scene-format.md): every kind of bad input is
// reported with its exact one-paragraph message "<file>:<line>:<column>: <key path>: <message>",
// and every shipped scene (scenes/default.yaml, scenes/examples/*.yaml) loads with the values it
// says.
//
// Line and column numbers in the expected messages count from 1 within the YAML text of each
// test; kLens below occupies lines 1-7, so text appended to it starts on line 8.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "scene/SceneLoader.h"
#include "tests/BuildPaths.h"
#include "tests/Tolerances.h"

namespace ltm {
namespace {

const std::string kSourceDir = ltm::test::source_dir();

// A valid double-convex lens, lines 1-7.
const std::string kLens =
    "object:\n"
    "  type: lens\n"
    "  r1: 50\n"
    "  r2: -50\n"
    "  center_thickness: 6\n"
    "  diameter: 25\n"
    "  ior: 1.5168\n";

// The full message of the SceneError that parsing `text` throws, or a marker if it parses.
std::string error_of(const std::string& text) {
    try {
        parse_scene(text, "scene.yaml");
    } catch (const SceneError& e) {
        return e.what();
    }
    return "(parsed without error)";
}

std::string load_error_of(const std::string& path) {
    try {
        load_scene(path);
    } catch (const SceneError& e) {
        return e.what();
    }
    return "(loaded without error)";
}

// ---------------------------------------------------------------------------------------------
// Unknown keys

TEST(SceneLoaderUnknownKey, TopLevelSuggestsTheNearestKey) {
    EXPECT_EQ(error_of(kLens + "camra:\n  samples_per_pixel: 4\n"),
              "scene.yaml:8:1: camra: unknown key 'camra' (did you mean 'camera'?)");
}

TEST(SceneLoaderUnknownKey, TopLevelWithoutNearMatchListsTheValidKeys) {
    EXPECT_EQ(error_of(kLens + "colour: red\n"),
              "scene.yaml:8:1: colour: unknown key 'colour'; valid keys are: object, defects, camera, display, "
              "mesh, tracing, seed, reference_seed");
}

TEST(SceneLoaderUnknownKey, InObjectSuggestsTheNearestKey) {
    EXPECT_EQ(error_of(kLens + "  diamter: 25\n"),
              "scene.yaml:8:3: object.diamter: unknown key 'diamter' for a lens (did you mean 'diameter'?)");
}

TEST(SceneLoaderUnknownKey, LensThicknessSuggestsCenterThickness) {
    EXPECT_EQ(error_of("object:\n  type: lens\n  thickness: 6\n"),
              "scene.yaml:3:3: object.thickness: unknown key 'thickness' for a lens (did you mean "
              "'center_thickness'?)");
}

TEST(SceneLoaderUnknownKey, WindowRadiusSaysWindowsAreFlat) {
    EXPECT_EQ(error_of("object:\n  type: window\n  thickness: 5\n  r1: 50\n"),
              "scene.yaml:4:3: object.r1: unknown key 'r1' for a window: windows have flat faces (use type: lens "
              "for curved faces); valid keys are: type, thickness, diameter, ior, rim, absorption, index_field");
}

TEST(SceneLoaderUnknownKey, WindowCenterThicknessSuggestsThickness) {
    EXPECT_EQ(error_of("object:\n  type: window\n  center_thickness: 5\n"),
              "scene.yaml:3:3: object.center_thickness: unknown key 'center_thickness' for a window (did you mean "
              "'thickness'?)");
}

TEST(SceneLoaderUnknownKey, InDefectSuggestsTheNearestKey) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, 0, 0], radus: 0.1}\n"),
              "scene.yaml:9:39: defects[0].radus: unknown key 'radus' for a bubble (did you mean 'radius'?)");
}

TEST(SceneLoaderUnknownKey, ScratchKeyInABubbleNamesItsOwner) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, 0, 0], radius: 0.1, width: 3}\n"),
              "scene.yaml:9:52: defects[0].width: unknown key 'width' for a bubble (width is a key of scratches); "
              "valid keys are: type, center, radius, semi_axes, rotation, surface_breaking");
}

TEST(SceneLoaderUnknownKey, ParticlesCannotBeSurfaceBreaking) {
    EXPECT_EQ(error_of(kLens + "defects:\n"
                               "  - type: particle\n"
                               "    center: [0, 0, 0]\n"
                               "    radius: 0.1\n"
                               "    surface_breaking: true\n"),
              "scene.yaml:12:5: defects[0].surface_breaking: unknown key 'surface_breaking' for a particle: "
              "particles always lie strictly inside the glass (a surface-breaking void is a bubble); valid keys "
              "are: type, center, radius, semi_axes, rotation");
}

TEST(SceneLoaderUnknownKey, ArcKeyAtScratchLevelPointsIntoArc) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: scratch, surface: front, radius: 3, width: 0.05, depth: 0.02}\n"),
              "scene.yaml:9:37: defects[0].radius: unknown key 'radius' for a scratch: an arc scratch takes radius "
              "inside arc: {center, radius, start_angle, end_angle}");
}

TEST(SceneLoaderUnknownKey, InsideArc) {
    EXPECT_EQ(error_of(kLens + "defects:\n"
                               "  - type: scratch\n"
                               "    surface: back\n"
                               "    arc: {center: [0, 0], radius: 3, start_angle: 0, end_anlge: 90}\n"),
              "scene.yaml:11:54: defects[0].arc.end_anlge: unknown key 'end_anlge' (did you mean 'end_angle'?)");
}

// ---------------------------------------------------------------------------------------------
// Wrong types

TEST(SceneLoaderWrongType, StringForANumber) {
    EXPECT_EQ(error_of("object:\n  type: lens\n  r1: 50\n  r2: -50\n  center_thickness: six\n"),
              "scene.yaml:5:21: object.center_thickness: expected a number, got 'six'");
}

TEST(SceneLoaderWrongType, StringForARadiusMentionsInf) {
    EXPECT_EQ(error_of("object:\n  type: lens\n  r1: flat\n"),
              "scene.yaml:3:7: object.r1: expected a number or inf, got 'flat'");
}

TEST(SceneLoaderWrongType, QuotedNumberIsAString) {
    EXPECT_EQ(error_of("object:\n  type: lens\n  r1: 50\n  r2: -50\n  center_thickness: \"6\"\n"),
              "scene.yaml:5:21: object.center_thickness: expected a number, got the quoted string \"6\"");
}

TEST(SceneLoaderWrongType, ScalarForAList) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: 5, radius: 0.1}\n"),
              "scene.yaml:9:28: defects[0].center: expected a list of 3 numbers [x, y, z], got '5'");
}

TEST(SceneLoaderWrongType, ListOfTheWrongLength) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, 0], radius: 0.1}\n"),
              "scene.yaml:9:28: defects[0].center: expected a list of 3 numbers [x, y, z], got a list of 2 items");
}

TEST(SceneLoaderWrongType, ScratchEndPointOfTheWrongLength) {
    EXPECT_EQ(error_of(kLens + "defects:\n"
                               "  - type: scratch\n"
                               "    surface: front\n"
                               "    start: [0, 0, 0, 0]\n"),
              "scene.yaml:11:12: defects[0].start: expected a list of 2 or 3 numbers [x, y] or [x, y, z], got a "
              "list of 4 items");
}

TEST(SceneLoaderWrongType, StringInsideAList) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, zero, 0], radius: 0.1}\n"),
              "scene.yaml:9:32: defects[0].center[1]: expected a number, got 'zero'");
}

TEST(SceneLoaderWrongType, FloatForAResolution) {
    EXPECT_EQ(error_of(kLens + "camera:\n  resolution: [100.5, 100]\n"),
              "scene.yaml:9:16: camera.resolution[0]: expected a positive integer, got '100.5'");
}

TEST(SceneLoaderWrongType, ZeroResolution) {
    EXPECT_EQ(error_of(kLens + "display:\n  resolution: [500, 0]\n"),
              "scene.yaml:9:21: display.resolution[1]: expected a positive integer, got '0'");
}

TEST(SceneLoaderWrongType, MappingWhereAListOfDefectsBelongs) {
    EXPECT_EQ(error_of(kLens + "defects:\n  type: bubble\n"),
              "scene.yaml:9:3: defects: expected a list of defects, got a mapping");
}

TEST(SceneLoaderWrongType, EmptySection) {
    EXPECT_EQ(error_of(kLens + "camera:\n"), "scene.yaml:8:1: camera: expected a mapping, got an empty value");
}

TEST(SceneLoaderWrongType, BooleanMustBeTrueOrFalse) {
    EXPECT_EQ(error_of(kLens + "mesh:\n  always_boolean: yes\n"),
              "scene.yaml:9:19: mesh.always_boolean: expected true or false, got 'yes'");
}

TEST(SceneLoaderWrongType, UnknownChoiceSuggestsTheNearest) {
    EXPECT_EQ(error_of("object:\n  type: lense\n"),
              "scene.yaml:2:9: object.type: expected lens, window or sphere, got 'lense' (did you mean 'lens'?)");
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubbel}\n"),
              "scene.yaml:9:12: defects[0].type: expected bubble, scratch, particle or inhomogeneity, got 'bubbel' (did you mean "
              "'bubble'?)");
}

TEST(SceneLoaderWrongType, NegativeSeed) {
    EXPECT_EQ(error_of(kLens + "seed: -1\n"), "scene.yaml:8:7: seed: expected a non-negative integer, got '-1'");
}

// ---------------------------------------------------------------------------------------------
// Non-finite numbers

TEST(SceneLoaderNonFinite, NanIsRejected) {
    EXPECT_EQ(error_of("object:\n  type: lens\n  r1: .nan\n"),
              "scene.yaml:3:7: object.r1: expected a number or inf, got '.nan' (not a number)");
    EXPECT_EQ(error_of(kLens + "display:\n  z: nan\n"),
              "scene.yaml:9:6: display.z: expected a finite number, got 'nan' (not a number)");
}

TEST(SceneLoaderNonFinite, InfOnlyForRadii) {
    EXPECT_EQ(error_of("object:\n  type: window\n  thickness: .inf\n"),
              "scene.yaml:3:14: object.thickness: expected a finite number, got '.inf'");
}

// ---------------------------------------------------------------------------------------------
// Missing and duplicate keys, malformed and unreadable files

TEST(SceneLoaderStructure, MissingRequiredKeyIsReportedAtItsMapping) {
    EXPECT_EQ(error_of("seed: 3\nobject:\n  type: lens\n  r1: 50\n  r2: -50\n  center_thickness: 6\n  ior: 1.5\n"),
              "scene.yaml:3:3: object.diameter: missing required key 'diameter'");
}

TEST(SceneLoaderStructure, MissingObject) {
    EXPECT_EQ(error_of("seed: 3\n"), "scene.yaml:1:1: object: missing required key 'object'");
}

TEST(SceneLoaderStructure, MissingSphereOrEllipsoidSize) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, 0, 0]}\n"),
              "scene.yaml:9:5: defects[0]: missing required key 'radius' (a sphere) or 'semi_axes' (an ellipsoid)");
}

TEST(SceneLoaderStructure, MissingScratchPath) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: scratch, surface: front, width: 0.05, depth: 0.02}\n"),
              "scene.yaml:9:5: defects[0]: missing required key 'start' and 'end' (a straight scratch) or 'arc' "
              "(a circular one)");
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: scratch, surface: front, start: [0, 0], width: 0.05, depth: 0.02}\n"),
              "scene.yaml:9:5: defects[0].end: missing required key 'end' (a straight scratch needs start and end)");
}

TEST(SceneLoaderStructure, DuplicateKey) {
    EXPECT_EQ(error_of(kLens + "  ior: 1.6\n"), "scene.yaml:8:3: object.ior: duplicate key 'ior' (first given on line 7)");
}

TEST(SceneLoaderStructure, DuplicateKeyInAFlowMapping) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, 0, 0], radius: 0.1, radius: 0.2}\n"),
              "scene.yaml:9:52: defects[0].radius: duplicate key 'radius' (first given on line 9)");
}

TEST(SceneLoaderStructure, ConflictingKeys) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, 0, 0], radius: 0.1, semi_axes: [1, 1, 1]}\n"),
              "scene.yaml:9:52: defects[0].semi_axes: give either radius (a sphere) or semi_axes (an ellipsoid), "
              "not both");
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, 0, 0], radius: 0.1, rotation: [0, 0, 3]}\n"),
              "scene.yaml:9:52: defects[0].rotation: rotation applies only to an ellipsoid given by semi_axes: a "
              "sphere (radius) has no orientation");
}

TEST(SceneLoaderStructure, MalformedYaml) {
    // yaml-cpp's own message and mark (where its parser stopped), prefixed.
    EXPECT_EQ(error_of("object:\n  type: lens\n  r1: [50, 3\n"),
              "scene.yaml:4:1: malformed YAML: end of sequence flow not found");
}

TEST(SceneLoaderStructure, EmptyFileAndWrongRoot) {
    EXPECT_EQ(error_of(""), "scene.yaml:1:1: the scene file is empty: expected a mapping with at least the key 'object'");
    EXPECT_EQ(error_of("- object\n"),
              "scene.yaml:1:1: expected a mapping of scene keys (object, defects, camera, display, mesh, tracing, seed, reference_seed) at "
              "the top level, got a list of 1 item");
}

TEST(SceneLoaderStructure, SeveralDocuments) {
    EXPECT_EQ(error_of(kLens + "---\nseed: 2\n"),
              "scene.yaml:9:1: the file holds 2 YAML documents (separated by ---); a scene file holds one");
}

TEST(SceneLoaderStructure, UnreadableFile) {
    const std::string missing = kSourceDir + "/scenes/no-such-scene.yaml";
    EXPECT_EQ(load_error_of(missing), missing + ": cannot read scene file: No such file or directory");
    const std::string folder = kSourceDir + "/scenes";
    EXPECT_EQ(load_error_of(folder), folder + ": cannot read scene file: Is a directory");
}

TEST(SceneLoaderStructure, ErrorCarriesItsParts) {
    try {
        parse_scene(kLens + "defects:\n  - {type: bubble, center: [0, 0, 0], radius: -0.1}\n", "parts.yaml");
        FAIL() << "expected a SceneError";
    } catch (const SceneError& e) {
        EXPECT_EQ(e.file, "parts.yaml");
        EXPECT_EQ(e.line, 9);
        EXPECT_EQ(e.column, 47);
        EXPECT_EQ(e.key_path, "defects[0].radius");
        EXPECT_EQ(e.message, "must be a positive length (mm), got -0.1");
    }
}

TEST(SceneLoaderStructure, FirstProblemInFileOrderWins) {
    // Both the object's ior and the camera's resolution are wrong: the earlier one is reported.
    EXPECT_EQ(error_of("object:\n  type: lens\n  ior: high\ncamera: {resolution: [1.5, 2]}\n"),
              "scene.yaml:3:8: object.ior: expected a number, got 'high'");
}

// ---------------------------------------------------------------------------------------------
// Value ranges and impossible geometry

TEST(SceneLoaderGeometry, RadiusSmallerThanSemiDiameter) {
    // Lens::problems' message, at the value of r1.
    EXPECT_EQ(error_of("object:\n  type: lens\n  r1: 10\n  r2: -50\n  center_thickness: 6\n  diameter: 25\n  ior: 1.5\n"),
              "scene.yaml:3:7: object.r1: |r1| = 10 mm is smaller than the semi-diameter 12.5 mm: the spherical "
              "surface cannot span the aperture");
}

TEST(SceneLoaderGeometry, NonPositiveEdgeThickness) {
    // t + sag(r2, a) - sag(r1, a) with a = 12.5, R = -+20: sag = 20 - sqrt(400 - 156.25) = 4.3875,
    // so 2 - 2 x 4.3875 = -6.77501 mm.
    EXPECT_EQ(error_of("object:\n  type: lens\n  r1: 20\n  r2: -20\n  center_thickness: 2\n  diameter: 25\n  ior: 1.5\n"),
              "scene.yaml:5:21: object.center_thickness: edge thickness t + sag(r2) - sag(r1) = -6.77501 mm is not "
              "positive: the faces cross before the rim (increase center_thickness or reduce diameter)");
}

TEST(SceneLoaderGeometry, IorNotAboveOne) {
    EXPECT_EQ(error_of("object:\n  type: lens\n  r1: 50\n  r2: -50\n  center_thickness: 6\n  diameter: 25\n  ior: 0.9\n"),
              "scene.yaml:7:8: object.ior: the glass's refractive index must be > 1 (got 0.9)");
}

TEST(SceneLoaderGeometry, WindowThicknessIsReportedUnderItsOwnKey) {
    EXPECT_EQ(error_of("object:\n  type: window\n  thickness: -1\n  diameter: 25\n  ior: 1.5\n"),
              "scene.yaml:3:14: object.thickness: must be a positive finite length (got -1)");
}

TEST(SceneLoaderGeometry, NegativeBubbleRadius) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, 0, 0], radius: -0.1}\n"),
              "scene.yaml:9:47: defects[0].radius: must be a positive length (mm), got -0.1");
}

TEST(SceneLoaderGeometry, ZeroSemiAxis) {
    EXPECT_EQ(error_of(kLens + "defects:\n  - {type: particle, center: [0, 0, 0], semi_axes: [0.2, 0, 0.1]}\n"),
              "scene.yaml:9:58: defects[0].semi_axes[1]: must be a positive length (mm), got 0");
}

TEST(SceneLoaderGeometry, OutOfRangeCameraAndMesh) {
    EXPECT_EQ(error_of(kLens + "camera:\n  numerical_aperture: 1\n"),
              "scene.yaml:9:23: camera.numerical_aperture: must be in (0, 1), got 1");
    EXPECT_EQ(error_of(kLens + "mesh:\n  defect_relative_tolerance: 0.6\n"),
              "scene.yaml:9:30: mesh.defect_relative_tolerance: must be in (0, 0.5], got 0.6");
    EXPECT_EQ(error_of(kLens + "camera:\n  size: [25, 0]\n"),
              "scene.yaml:9:14: camera.size[1]: must be a positive length (mm), got 0");
}

TEST(SceneLoaderGeometry, ArcAngles) {
    const std::string head = kLens + "defects:\n  - type: scratch\n    surface: front\n    width: 0.05\n    depth: 0.02\n";
    EXPECT_EQ(error_of(head + "    arc: {center: [0, 0], radius: 3, start_angle: 30, end_angle: 10}\n"),
              "scene.yaml:13:66: defects[0].arc.end_angle: must be greater than start_angle (30), got 10");
    EXPECT_EQ(error_of(head + "    arc: {center: [0, 0], radius: 3, start_angle: -90, end_angle: 270}\n"),
              "scene.yaml:13:67: defects[0].arc.end_angle: the arc spans 360 degrees from start_angle -90: it must "
              "span less than 360");
}

// Placement problems come from defect_problems() (defects/DefectSolid.cpp, owned by the defects
// layer): their wording is that layer's, so these tests pin the location and key path exactly and
// only a distinctive part of the message.
TEST(SceneLoaderGeometry, BubbleOutsideTheGlassNotDeclaredSurfaceBreaking) {
    const std::string e = error_of(kLens + "defects:\n"
                                           "  - {type: bubble, center: [0, 0, 0], radius: 0.1}\n"
                                           "  - {type: bubble, center: [0, 0, 10], radius: 0.1}\n");
    EXPECT_EQ(e.rfind("scene.yaml:10:28: defects[1].center: ", 0), 0u) << e;
    EXPECT_NE(e.find("outside the glass"), std::string::npos) << e;
    // A pit there would cut nothing: no advice to declare one.
    EXPECT_EQ(e.find("surface_breaking"), std::string::npos) << e;
}

// A void that holds the whole lens (its farthest point from the origin is on the edge circles,
// hypot(12.5, 3 - sag(50, 12.5)) = 12.5795 mm away) is refused at its size, pit or not, and the
// message advises no pit.
TEST(SceneLoaderGeometry, VoidThatHoldsTheObject) {
    for (const char* breaking : {", surface_breaking: true", ""})
        EXPECT_EQ(error_of(kLens + "defects:\n  - {type: bubble, center: [0, 0, 0], radius: 200" + breaking + "}\n"),
                  "scene.yaml:9:47: defects[0].radius: the bubble at (0, 0, 0) (radius 200 mm) holds the whole object, "
                  "whose every point lies within 12.5795 mm of its centre: it would leave no glass (lengths are in mm)")
            << breaking;
}

TEST(SceneLoaderGeometry, ScratchOffItsSurface) {
    // The front face's vertex is at z = -3; a start point given at z = +1 is 4 mm off it.
    const std::string e = error_of(kLens + "defects:\n"
                                           "  - type: scratch\n"
                                           "    surface: front\n"
                                           "    start: [0, 0, 1]\n"
                                           "    end: [2, 0]\n"
                                           "    width: 0.05\n"
                                           "    depth: 0.02\n");
    EXPECT_EQ(e.rfind("scene.yaml:11:12: defects[0].start: ", 0), 0u) << e;
    EXPECT_NE(e.find("off the front face"), std::string::npos) << e;
}

TEST(SceneLoaderGeometry, DisplayInsideTheObject) {
    // Double-convex: the back extent is the back vertex, z = t/2 = 3.
    EXPECT_EQ(error_of(kLens + "display:\n  z: 2\n"),
              "scene.yaml:9:6: display.z: the display must lie behind the object: z must be greater than 3 mm (the "
              "object's back extent), got 2");
    // Positive meniscus (r1 = 30, r2 = 60, t = 4, a = 12.5): the back face bends toward +z, its rim
    // is at 2 + 60 - sqrt(3600 - 156.25) = 3.31653 mm, beyond the vertex at 2.
    EXPECT_EQ(error_of("object: {type: lens, r1: 30, r2: 60, center_thickness: 4, diameter: 25, ior: 1.5}\n"
                       "display: {z: 3.3}\n"),
              "scene.yaml:2:14: display.z: the display must lie behind the object: z must be greater than 3.31653 "
              "mm (the object's back extent), got 3.3");
}

TEST(SceneLoaderGeometry, DefaultDisplayInsideAThickObject) {
    // No display section: the default z = 60 is checked too, and reported at the document.
    EXPECT_EQ(error_of("object: {type: window, thickness: 130, diameter: 25, ior: 1.5}\n"),
              "scene.yaml:1:1: display.z: the display must lie behind the object: z must be greater than 65 mm (the "
              "object's back extent), got 60 (the default)");
}

// ---------------------------------------------------------------------------------------------
// Successful parses

TEST(SceneLoaderValid, DefaultScene) {
    const Scene s = load_scene(kSourceDir + "/scenes/default.yaml");
    EXPECT_EQ(s.source, kSourceDir + "/scenes/default.yaml");
    EXPECT_EQ(s.object.type, ObjectType::Lens);
    EXPECT_EQ(s.object.lens.r1, 50.0);
    EXPECT_EQ(s.object.lens.r2, -50.0);
    EXPECT_EQ(s.object.lens.center_thickness, 6.0);
    EXPECT_EQ(s.object.lens.diameter, 25.0);
    EXPECT_EQ(s.object.lens.ior, 1.5168);
    EXPECT_EQ(s.object.rim, RimFinish::Polished);
    ASSERT_EQ(s.defects.size(), 3u);
    const double xs[3] = {0.0, 4.0, 8.0};  // the centre, then equidistant steps toward the rim
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(s.defects[i].type, DefectType::Bubble);
        EXPECT_EQ(s.defects[i].center, Vec3(xs[i], 0.0, 0.0));
        EXPECT_EQ(s.defects[i].semi_axes, Vec3(0.1, 0.1, 0.1));
        EXPECT_TRUE(s.defects[i].is_sphere());
        EXPECT_FALSE(s.defects[i].surface_breaking);
    }
    EXPECT_EQ(s.camera.resolution, (std::array<int, 2>{100, 100}));
    EXPECT_EQ(s.camera.size, (std::array<double, 2>{25.0, 25.0}));
    EXPECT_EQ(s.camera.numerical_aperture, 0.01);
    EXPECT_EQ(s.camera.samples_per_pixel, 64);
    EXPECT_EQ(s.display.resolution, (std::array<int, 2>{500, 500}));
    EXPECT_EQ(s.display.size, (std::array<double, 2>{100.0, 100.0}));
    EXPECT_EQ(s.display.z, 60.0);
    EXPECT_EQ(s.mesh.chord_tolerance, 1e-3);
    EXPECT_EQ(s.mesh.defect_relative_tolerance, 0.01);
    EXPECT_FALSE(s.mesh.always_boolean);
    EXPECT_EQ(s.seed, 1u);
}

TEST(SceneLoaderValid, EveryExampleLoads) {
    int count = 0;
    for (const auto& entry : std::filesystem::directory_iterator(kSourceDir + "/scenes/examples")) {
        if (entry.path().extension() != ".yaml") continue;
        ++count;
        EXPECT_NO_THROW(load_scene(entry.path().string())) << load_error_of(entry.path().string());
    }
    EXPECT_GE(count, 12);
}

Scene example(const std::string& name) { return load_scene(kSourceDir + "/scenes/examples/" + name); }

TEST(SceneLoaderValid, InfRadiiAreFlatAndPositive) {
    EXPECT_TRUE(std::isinf(example("plano-convex.yaml").object.lens.r1));
    EXPECT_GT(example("plano-convex.yaml").object.lens.r1, 0);
    EXPECT_EQ(example("plano-concave.yaml").object.lens.r1, INFINITY);  // written .inf
    // Every accepted spelling; -inf is the same flat face and is stored as +inf.
    for (const char* r : {"inf", "+inf", "-inf", ".inf", "-.inf", "Infinity", "\"inf\"", "\"-inf\""}) {
        const Scene s = parse_scene(std::string("object: {type: lens, r1: ") + r +
                                        ", r2: -50, center_thickness: 6, diameter: 25, ior: 1.5}\n",
                                    "inf.yaml");
        EXPECT_EQ(s.object.lens.r1, INFINITY) << r;
    }
}

TEST(SceneLoaderValid, MeniscusAndConcaveSigns) {
    const Scene pos = example("positive-meniscus.yaml");
    EXPECT_EQ(pos.object.lens.r1, 30.0);
    EXPECT_EQ(pos.object.lens.r2, 60.0);
    const Scene bi = example("biconcave.yaml");
    EXPECT_EQ(bi.object.lens.r1, -50.0);
    EXPECT_EQ(bi.object.lens.r2, 50.0);
}

TEST(SceneLoaderValid, Window) {
    const Scene s = example("window.yaml");
    EXPECT_EQ(s.object.type, ObjectType::Window);
    EXPECT_EQ(s.object.lens.r1, INFINITY);
    EXPECT_EQ(s.object.lens.r2, INFINITY);
    EXPECT_EQ(s.object.lens.center_thickness, 5.0);
    EXPECT_EQ(s.object.rim, RimFinish::Absorbing);
}

TEST(SceneLoaderValid, EllipsoidRotationFrameIsOrthonormal) {
    const Scene s = example("ellipsoid-bubble.yaml");
    ASSERT_EQ(s.defects.size(), 1u);
    const Defect& d = s.defects[0];
    EXPECT_EQ(d.semi_axes, Vec3(0.3, 0.1, 0.1));
    EXPECT_FALSE(d.is_sphere());
    // F = Rz(45) Ry(0) Rx(0): each entry is a sum of at most 3 products of cos/sin values, each
    // correctly rounded (0.5 ulp), so F^T F - I and the expected columns agree to a few eps;
    // 8 eps is a 2x margin over the 4 rounded operations per entry.
    const double tol = 8.0 * tol::kEps;
    const Mat3 ftf = d.frame.transposed() * d.frame;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(ftf(r, c), r == c ? 1.0 : 0.0, tol) << r << "," << c;
    EXPECT_NEAR(dot(cross(d.frame.column(0), d.frame.column(1)), d.frame.column(2)), 1.0, tol);  // right-handed
    const double h = std::sqrt(0.5);
    EXPECT_NEAR(d.frame.column(0).x, h, tol);  // the long axis turned 45 degrees about +z
    EXPECT_NEAR(d.frame.column(0).y, h, tol);
    EXPECT_NEAR(d.frame.column(0).z, 0.0, tol);
}

TEST(SceneLoaderValid, SphereHasTheIdentityFrame) {
    const Scene s = example("particle.yaml");
    ASSERT_EQ(s.defects.size(), 2u);
    EXPECT_EQ(s.defects[0].type, DefectType::Particle);
    EXPECT_EQ(s.defects[0].frame.m, Mat3::identity().m);
    EXPECT_EQ(s.defects[0].semi_axes, Vec3(0.08, 0.08, 0.08));
    EXPECT_EQ(s.defects[1].semi_axes, Vec3(0.15, 0.05, 0.05));
}

TEST(SceneLoaderValid, Pit) {
    const Scene s = example("pit.yaml");
    ASSERT_EQ(s.defects.size(), 1u);
    EXPECT_TRUE(s.defects[0].surface_breaking);
}

TEST(SceneLoaderValid, StraightScratch) {
    const Scene s = example("scratch-v-front.yaml");
    ASSERT_EQ(s.defects.size(), 1u);
    const Defect& d = s.defects[0];
    EXPECT_EQ(d.type, DefectType::Scratch);
    EXPECT_EQ(d.side, 0);
    EXPECT_FALSE(d.arc);
    EXPECT_EQ(d.start.x, -5.0);
    EXPECT_EQ(d.end.y, 2.0);
    EXPECT_FALSE(d.start_has_z);
    EXPECT_FALSE(d.end_has_z);
    EXPECT_EQ(d.width, 0.05);
    EXPECT_EQ(d.depth, 0.02);
    EXPECT_EQ(d.profile, ScratchProfile::V);
}

TEST(SceneLoaderValid, ArcScratch) {
    const Scene s = example("scratch-u-arc-back.yaml");
    ASSERT_EQ(s.defects.size(), 1u);
    const Defect& d = s.defects[0];
    EXPECT_EQ(d.side, 1);
    EXPECT_TRUE(d.arc);
    EXPECT_EQ(d.arc_center, Vec3(0, 0, 0));
    EXPECT_FALSE(d.arc_center_has_z);
    EXPECT_EQ(d.arc_radius, 6.0);
    EXPECT_EQ(d.start_angle, 0.0);
    EXPECT_EQ(d.end_angle, 90.0);
    EXPECT_EQ(d.profile, ScratchProfile::U);
}

TEST(SceneLoaderValid, ScratchPointWithZOnTheFace) {
    // z of the front face at (0, 0) is its vertex, -t/2 = -3.
    const Scene s = parse_scene(kLens + "defects:\n"
                                        "  - {type: scratch, surface: front, start: [0, 0, -3], end: [2, 0], "
                                        "width: 0.05, depth: 0.02}\n",
                                "z.yaml");
    EXPECT_TRUE(s.defects[0].start_has_z);
    EXPECT_EQ(s.defects[0].start.z, -3.0);
    EXPECT_FALSE(s.defects[0].end_has_z);
}

TEST(SceneLoaderValid, DefectFreeAndDefaults) {
    for (const char* tail : {"", "defects:\n", "defects: []\n"}) {
        const Scene s = parse_scene(kLens + tail, "free.yaml");
        EXPECT_TRUE(s.defects.empty()) << tail;
        EXPECT_EQ(s.camera.resolution, (std::array<int, 2>{100, 100}));
        EXPECT_EQ(s.display.z, 60.0);
        EXPECT_EQ(s.seed, 1u);
    }
    EXPECT_EQ(parse_scene(kLens + "seed: 18446744073709551615\n", "seed.yaml").seed, 18446744073709551615ull);
}

TEST(SceneLoaderValid, OverlappingDefects) {
    EXPECT_EQ(example("overlapping-defects.yaml").defects.size(), 4u);
}

TEST(SceneLoaderTracing, EstimatorAndDepth) {
    const Scene plain = parse_scene(kLens, "scene.yaml");
    EXPECT_EQ(plain.tracing.estimator, Estimator::Sample);
    const Scene split = parse_scene(kLens + "tracing: {estimator: split}\n", "scene.yaml");
    EXPECT_EQ(split.tracing.estimator, Estimator::Split);
    EXPECT_EQ(split.tracing.split_depth, kDefaultSplitDepth);
    // The order of the keys does not matter; 0 and the maximum are valid depths.
    const Scene deep = parse_scene(kLens + "tracing:\n  split_depth: 16\n  estimator: split\n", "scene.yaml");
    EXPECT_EQ(deep.tracing.split_depth, kMaxSplitDepth);
    EXPECT_EQ(parse_scene(kLens + "tracing: {estimator: split, split_depth: 0}\n", "s.yaml").tracing.split_depth, 0);
    EXPECT_EQ(error_of(kLens + "tracing: {estimator: split, split_depth: 17}\n"),
              "scene.yaml:8:42: tracing.split_depth: expected an integer in [0, 16] (Fresnel interactions split) "
              "(at most 16), got '17'");
    EXPECT_EQ(error_of(kLens + "tracing:\n  estimator: sample\n  split_depth: 2\n"),
              "scene.yaml:10:3: tracing.split_depth: applies only to 'estimator: split' (the estimator here is "
              "sample); remove it or add 'estimator: split'");
    EXPECT_EQ(error_of(kLens + "tracing: {estimator: Split}\n"),
              "scene.yaml:8:22: tracing.estimator: expected sample or split, got 'Split' (did you mean 'split'?)");
}

}  // namespace
}  // namespace ltm
