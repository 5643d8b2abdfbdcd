// The strict YAML engine (scene/StrictYaml.h) on its own, as a format other than a scene file uses
// it, and a scene held inline in such a file (parse_scene_node): errors of the inline scene are
// reported at their lines in the enclosing file, behind the scene's key path.
//
// The format here is a stand-in for a dataset spec: `count` (a positive integer), `jitter`
// (a number), `scene` (an inline scene, required).
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "io/Json.h"
#include "scene/SceneJson.h"
#include "scene/SceneLoader.h"
#include "scene/StrictYaml.h"
#include "tests/BuildPaths.h"

namespace ltm {
namespace {

struct Spec {
    int count = 1;
    double jitter = 0;
    Scene scene;
};

Spec read_spec(const std::string& text, const std::string& file) {
    const yaml::Reader r(file);
    const YAML::Node root = yaml::parse_document(text, file, "dataset spec");
    if (!root.IsMap()) r.fail(yaml::loc_of(root), "", "expected a mapping, got " + yaml::describe(root));
    Spec spec;
    yaml::Where where;
    yaml::KeyRule rule;
    rule.keys = {"count", "jitter", "scene"};
    rule.context = " for a dataset spec";
    r.walk(root, "", rule, [&](const yaml::Item& e) {
        where[e.key] = e.value_loc();
        if (e.key == "count") {
            spec.count = r.positive_int(e.value, e.value_loc(), e.key);
        } else if (e.key == "jitter") {
            spec.jitter = r.number(e.value, e.value_loc(), e.key);
        } else if (e.key == "scene") {
            r.require_map(e, e.key);
            spec.scene = parse_scene_node(e.value, file, "scene");
        }
    });
    r.require_keys(root, "", where, {"scene"});
    return spec;
}

std::string error_of(const std::string& text) {
    try {
        read_spec(text, "spec.yaml");
    } catch (const InputError& e) {
        return e.what();
    }
    return "(read without error)";
}

const std::string kObject =
    "{type: lens, r1: 50, r2: -50, center_thickness: 6, diameter: 25, ior: 1.5168}";

// ---------------------------------------------------------------------------------------------
// The engine

TEST(StrictYaml, UnknownKeySuggestsTheNearest) {
    EXPECT_EQ(error_of("cont: 3\n"), "spec.yaml:1:1: cont: unknown key 'cont' for a dataset spec (did you mean 'count'?)");
    EXPECT_EQ(error_of("colour: red\n"),
              "spec.yaml:1:1: colour: unknown key 'colour' for a dataset spec; valid keys are: count, jitter, scene");
}

TEST(StrictYaml, DuplicateKey) {
    EXPECT_EQ(error_of("count: 3\njitter: 0.1\ncount: 4\n"),
              "spec.yaml:3:1: count: duplicate key 'count' (first given on line 1)");
}

TEST(StrictYaml, WrongTypes) {
    EXPECT_EQ(error_of("count: 2.5\n"), "spec.yaml:1:8: count: expected a positive integer, got '2.5'");
    EXPECT_EQ(error_of("jitter: \"0.1\"\n"), "spec.yaml:1:9: jitter: expected a number, got the quoted string \"0.1\"");
    EXPECT_EQ(error_of("jitter: .nan\n"), "spec.yaml:1:9: jitter: expected a finite number, got '.nan' (not a number)");
    EXPECT_EQ(error_of("count: 3\nscene: [1, 2]\n"), "spec.yaml:2:8: scene: expected a mapping, got a list of 2 items");
    EXPECT_EQ(error_of("scene:\ncount: 3\n"), "spec.yaml:1:1: scene: expected a mapping, got an empty value");
}

// A number beyond the largest double (about 1.797e308) is refused, never rounded to infinity:
// only the words mean inf (a radius of 1e400 would otherwise silently become a flat face).
// Below the smallest subnormal (4.9e-324) numbers round to 0, as strtod does; -0 reads as 0.
TEST(StrictYaml, NumbersBeyondADouble) {
    EXPECT_EQ(error_of("jitter: 1e400\n"), "spec.yaml:1:9: jitter: 1e400 is beyond the range of a double (about 1.8e308)");
    EXPECT_EQ(error_of("jitter: -1.8e308\n"), "spec.yaml:1:9: jitter: -1.8e308 is beyond the range of a double (about 1.8e308)");
    EXPECT_EQ(error_of("jitter: 1.7e308\nscene: {}\n").find("jitter"), std::string::npos);
    double x = 1;
    EXPECT_EQ(yaml::parse_real("1e-400", x), yaml::Real::Number);
    EXPECT_EQ(x, 0.0);
    EXPECT_EQ(yaml::parse_real("-0", x), yaml::Real::Number);
    EXPECT_EQ(x, 0.0);
    EXPECT_EQ(yaml::parse_real("-.inf", x), yaml::Real::Infinite);
    EXPECT_EQ(yaml::parse_real("1e309", x), yaml::Real::Overflow);
}

TEST(StrictYaml, MissingKeyAtTheMappingThatLacksIt) {
    EXPECT_EQ(error_of("count: 3\n"), "spec.yaml:1:1: scene: missing required key 'scene'");
}

TEST(StrictYaml, DocumentsAreNamedByTheirKind) {
    EXPECT_EQ(error_of("count: 3\n---\ncount: 4\n"),
              "spec.yaml:3:1: the file holds 2 YAML documents (separated by ---); a dataset spec holds one");
    EXPECT_EQ(error_of("count: [3\n"), "spec.yaml:2:1: malformed YAML: end of sequence flow not found");
    try {
        yaml::parse_document("a: 1\n---\nb: 2\n", "x.yaml", "input file");
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(e.message, "the file holds 2 YAML documents (separated by ---); an input file holds one");
    }
    EXPECT_TRUE(yaml::parse_document("", "empty.yaml", "dataset spec").IsNull());
}

// YAML indents with spaces only (YAML 1.2, section 6.1: "tab characters must not be used in
// indentation"); yaml-cpp stops at such a tab with "illegal map value" and the like, which does not
// say why. The message names the tab at its own line and column. A tab that separates (after a
// key's colon, between the items of a [flow] list) is allowed YAML and reads as a space.
TEST(StrictYaml, ATabInTheIndentationIsNamedAtTheTab) {
    const std::string tab_message =
        "malformed YAML: a tab in the indentation (YAML does not allow tabs for indentation; use spaces)";
    // yaml-cpp: "illegal map value" at 3:8 (after the key), the tab is 3:1.
    EXPECT_EQ(error_of("count: 3\nscene:\n\tseed: 1\n"), "spec.yaml:3:1: " + tab_message);
    // "illegal tab when looking for indentation" at the tab itself, after two spaces.
    EXPECT_EQ(error_of("count: 3\nscene:\n  seed: 1\n  \tobject: {}\n"), "spec.yaml:4:3: " + tab_message);
    // After a block sequence's "- ": yaml-cpp reports "illegal map value" at 3:7.
    EXPECT_EQ(error_of("count: 3\nscene:\n  -\ta: 1\n     b: 2\n"), "spec.yaml:3:4: " + tab_message);
    // Separation tabs parse, and other malformed YAML keeps yaml-cpp's own reason.
    EXPECT_EQ(error_of("count:\t3\njitter: [1,\n\t2]\nscene: {}\n"),
              "spec.yaml:2:9: jitter: expected a number, got a list of 2 items");
    EXPECT_EQ(error_of("count: 3\n\tjitter: [1\n"), "spec.yaml:2:1: " + tab_message);
    EXPECT_EQ(error_of("count: 3 \t# a comment\njitter: [1\n"),
              "spec.yaml:3:1: malformed YAML: end of sequence flow not found");
}

TEST(StrictYaml, UnreadableFile) {
    const std::string missing = ltm::test::source_dir() + "/scenes/no-such-spec.yaml";
    try {
        yaml::load_document(missing, "dataset spec");
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), missing + ": cannot read dataset spec: No such file or directory");
        EXPECT_EQ(e.line, 0);
    }
}

TEST(StrictYaml, PrefixGoesBeforeEveryKeyPath) {
    const yaml::Reader r("spec.yaml", "variants[2]");
    const YAML::Node root = yaml::parse_document("seed: -1\n", "spec.yaml", "dataset spec");
    try {
        r.seed(root["seed"], yaml::loc_of(root["seed"]), "seed");
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), "spec.yaml:1:7: variants[2].seed: expected a non-negative integer, got '-1'");
    }
}

TEST(StrictYaml, Words) {
    EXPECT_EQ(yaml::nearest("thickness", {"center_thickness", "diameter"}).value_or(""), "center_thickness");
    EXPECT_FALSE(yaml::nearest("xy", {"center", "radius"}).has_value());
    EXPECT_EQ(yaml::list_words({"V", "U"}, " or "), "V or U");
    EXPECT_EQ(yaml::join_path("camera", "size"), "camera.size");
    EXPECT_EQ(yaml::join_path("size", "[1]"), "size[1]");
    EXPECT_EQ(yaml::join_path("", "seed"), "seed");
    EXPECT_EQ(yaml::join_path("scene", ""), "scene");
    yaml::Where where{{"arc", {4, 5}}, {"center", {6, 7}}};
    EXPECT_EQ(yaml::located(where, "arc.radius", {1, 1}).line, 4);
    EXPECT_EQ(yaml::located(where, "center[2]", {1, 1}).column, 7);
    EXPECT_EQ(yaml::located(where, "width", {9, 9}).line, 9);
}

// ---------------------------------------------------------------------------------------------
// A scene inside the spec

TEST(InlineScene, ParsesAsTheSameSceneFile) {
    const std::string scene_keys = "object: " + kObject + ", camera: {samples_per_pixel: 4}, seed: 7";
    const Spec spec = read_spec("count: 3\nscene: {" + scene_keys + "}\n", "spec.yaml");
    EXPECT_EQ(spec.count, 3);
    EXPECT_EQ(spec.scene.source, "spec.yaml");
    const Scene file = parse_scene("{" + scene_keys + "}\n", "spec.yaml");
    EXPECT_EQ(scene_to_json(spec.scene), scene_to_json(file));
    EXPECT_EQ(spec.scene.camera.samples_per_pixel, 4);
    EXPECT_EQ(spec.scene.seed, 7u);
}

TEST(InlineScene, ErrorsAtTheirLinesInTheSpec) {
    // A block scene from line 2; its keys are indented by 2.
    EXPECT_EQ(error_of("count: 3\nscene:\n  object: " + kObject + "\n  camra: {samples_per_pixel: 4}\n"),
              "spec.yaml:4:3: scene.camra: unknown key 'camra' (did you mean 'camera'?)");
    EXPECT_EQ(error_of("count: 3\nscene:\n  object:\n    type: lens\n    r1: 50\n    ior: 1.5\n    ior: 1.6\n"),
              "spec.yaml:7:5: scene.object.ior: duplicate key 'ior' (first given on line 6)");
    // An inline (flow) scene on line 1.
    EXPECT_EQ(error_of("scene: {object: {type: lens, r1: 50, r2: -50, center_thickness: 6, diameter: 25, ior: 0.9}}\n"),
              "spec.yaml:1:87: scene.object.ior: the glass's refractive index must be > 1 (got 0.9)");
    EXPECT_EQ(error_of("scene: {object: " + kObject + ", defects: [{type: bubble, center: [0, 0, 9], radius: 0.1}]}\n"),
              "spec.yaml:1:129: scene.defects[0].center: the bubble at (0, 0, 9) lies entirely outside the glass; "
              "an enclosed bubble must lie strictly inside it");
}

TEST(InlineScene, DocumentStartProblemsAtTheMapping) {
    EXPECT_EQ(error_of("count: 3\nscene: {camera: {samples_per_pixel: 4}}\n"),
              "spec.yaml:2:8: scene.object: missing required key 'object'");
    // A 130 mm window reaches z = 65, beyond the default display z = 60.
    EXPECT_EQ(error_of("count: 3\nscene: {object: {type: window, thickness: 130, diameter: 25, ior: 1.5}}\n"),
              "spec.yaml:2:8: scene.display.z: the display must lie behind the object: z must be greater than 65 mm "
              "(the object's back extent), got 60 (the default)");
}

TEST(InlineScene, NotAMapping) {
    const YAML::Node root = yaml::parse_document("scene: [1, 2]\n", "spec.yaml", "dataset spec");
    try {
        parse_scene_node(root["scene"], "spec.yaml", "scene");
        FAIL() << "expected a SceneError";
    } catch (const SceneError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "spec.yaml:1:8: scene: expected a mapping of scene keys (object, defects, camera, display, mesh, "
                  "tracing, seed, reference_seed), got a list of 2 items");
    }
    try {
        parse_scene_node(root["missing"], "spec.yaml", "scene");
        FAIL() << "expected a SceneError";
    } catch (const SceneError& e) {
        EXPECT_EQ(e.key_path, "scene");
        EXPECT_EQ(e.message,
                  "expected a mapping of scene keys (object, defects, camera, display, mesh, tracing, seed, reference_seed), got an empty value");
    }
}

TEST(InlineScene, WithoutPrefixThePathsOfAFile) {
    const YAML::Node root =
        yaml::parse_document("scene:\n  object: " + kObject + "\n  seed: -3\n", "spec.yaml", "dataset spec");
    try {
        parse_scene_node(root["scene"], "spec.yaml");
        FAIL() << "expected a SceneError";
    } catch (const SceneError& e) {
        EXPECT_EQ(std::string(e.what()), "spec.yaml:3:9: seed: expected a non-negative integer, got '-3'");
    }
}

}  // namespace
}  // namespace ltm

// yaml-cpp 0.7 loops forever on a ',' outside a flow collection (YAML::LoadAll(",") returns empty
// documents until memory runs out; fuzz/fuzz_scene reaches it). Here it is a located error.
TEST(StrictYaml, AStrayCommaIsAnErrorNotAHang) {
    for (const char* text : {",", "# c\n\n  ,\n", ", ,"}) {
        SCOPED_TRACE(text);
        try {
            ltm::yaml::parse_document(text, "s.yaml", "scene file");
            ADD_FAILURE() << "parsed";
        } catch (const ltm::InputError& e) {
            EXPECT_NE(std::string(e.what()).find("unexpected ','"), std::string::npos) << e.what();
            EXPECT_GE(e.line, 1);
        }
    }
    EXPECT_EQ(ltm::yaml::parse_document("a: 1\n", "s.yaml", "scene file")["a"].as<int>(), 1);
}
