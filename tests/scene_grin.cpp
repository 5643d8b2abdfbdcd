// The scene keys of graded-index glass (docs/scene-format.md: object type sphere,
// object.index_field, defects of type inhomogeneity, mesh.index_tolerance): what they load to,
// and the exact located message of every kind of bad input the issue lists (an index below 1 or
// an imaginary one anywhere in the object, an asymmetric Hessian, an inhomogeneity that misses
// the glass, delta_n = 0, an index_field where it cannot go) and of the other placement rules.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "scene/SceneLoader.h"

namespace ltm {
namespace {

std::string error_of(const std::string& text) {
    try {
        parse_scene(text, "scene.yaml");
    } catch (const SceneError& e) {
        return e.what();
    }
    return "(parsed without error)";
}

const std::string kWindow = "object: {type: window, thickness: 4, diameter: 20, ior: 1.5}\n";

TEST(SceneGrin, SphereIsTheBallOfItsRadius) {
    const Scene s = parse_scene("object: {type: sphere, radius: 10, ior: 1.4}\n", "scene.yaml");
    EXPECT_EQ(s.object.type, ObjectType::Sphere);
    EXPECT_TRUE(s.object.lens.ball);
    EXPECT_EQ(s.object.lens.r1, 10.0);
    EXPECT_EQ(s.object.lens.r2, -10.0);
    EXPECT_EQ(s.object.lens.center_thickness, 20.0);
    EXPECT_EQ(s.object.lens.diameter, 20.0);
    EXPECT_FALSE(s.object.index_field.graded());
}

TEST(SceneGrin, IndexFieldsLoadTheirParameters) {
    const Scene a = parse_scene(
        "object:\n  type: sphere\n  radius: 10.0\n  ior: 1.4142135623730951\n"
        "  index_field: {type: spherical_n2, g: 0.0707106781186548}\n",
        "scene.yaml");
    EXPECT_EQ(a.object.index_field.type, IndexFieldType::SphericalN2);
    EXPECT_EQ(a.object.index_field.g, 0.0707106781186548);
    EXPECT_EQ(a.object.index_field.ior, 1.4142135623730951);  // the object's ior
    const Scene b = parse_scene(
        "object:\n  type: lens\n  r1: 50\n  r2: -50\n  center_thickness: 6\n  diameter: 25\n  ior: 1.5\n"
        "  index_field:\n    type: quadratic_n2\n    gradient: [0.0, 0.0, 0.002]\n"
        "    hessian: [[-0.0008, 0.0001, 0.0], [0.0001, -0.0004, 0.0], [0.0, 0.0, 0.0]]\n",
        "scene.yaml");
    EXPECT_EQ(b.object.index_field.type, IndexFieldType::QuadraticN2);
    EXPECT_EQ(b.object.index_field.gradient.z, 0.002);
    EXPECT_EQ(b.object.index_field.hessian(0, 1), 0.0001);
    EXPECT_EQ(b.object.index_field.hessian(1, 1), -0.0004);
    const Scene c = parse_scene(
        "object: {type: window, thickness: 4, diameter: 20, ior: 1.5, index_field: {type: linear_n, gradient: [0.01, 0, 0]}}\n",
        "scene.yaml");
    EXPECT_EQ(c.object.index_field.type, IndexFieldType::LinearN);
    EXPECT_FALSE(c.object.index_field.closed_form());
}

TEST(SceneGrin, InhomogeneitiesLoadWithTheirDefaults) {
    const Scene s = parse_scene(kWindow +
                                    "defects:\n"
                                    "  - {type: inhomogeneity, center: [0, 0, 0], radius: 1, delta_n: 0.01}\n"
                                    "  - {type: inhomogeneity, center: [5, 0, 0], semi_axes: [1, 0.5, 0.3], "
                                    "rotation: [0, 0, 30], delta_n: -0.002, profile: uniform}\n"
                                    "mesh: {index_tolerance: 2e-4}\n",
                                "scene.yaml");
    ASSERT_EQ(s.defects.size(), 2u);
    EXPECT_EQ(s.defects[0].type, DefectType::Inhomogeneity);
    EXPECT_EQ(s.defects[0].index_profile, IndexProfile::Smooth);  // the default profile
    EXPECT_EQ(s.defects[0].delta_n, 0.01);
    EXPECT_EQ(s.defects[0].semi_axes.y, 1.0);
    EXPECT_EQ(s.defects[1].index_profile, IndexProfile::Uniform);
    EXPECT_EQ(s.defects[1].delta_n, -0.002);
    EXPECT_EQ(s.mesh.index_tolerance, 2e-4);
    EXPECT_EQ(parse_scene(kWindow, "scene.yaml").mesh.index_tolerance, MeshOptions{}.index_tolerance);
}

TEST(SceneGrin, AnIndexBelowOneAnywhereIsRefused) {
    // g = 0.08 in a ball of radius 10: n^2 = 2 (1 - 0.0064 |x|^2) = 0.72 at the surface, n = 0.8485;
    // the largest g that keeps n >= 1 is sqrt(1 - 1/ior^2) / R = 0.0707107.
    EXPECT_EQ(error_of("object:\n  type: sphere\n  radius: 10\n  ior: 1.4142135623730951\n"
                       "  index_field: {type: spherical_n2, g: 0.08}\n"),
              "scene.yaml:5:16: object.index_field: n = 0.848528 at (0, 0, -10) mm is below 1: no glass is optically "
              "thinner than vacuum (spherical_n2 keeps n >= 1 in this object for g <= sqrt(1 - 1/ior^2) / max |x| = "
              "0.0707107 1/mm)");
}

TEST(SceneGrin, AnImaginaryIndexAnywhereIsRefused) {
    // n^2 = 2.25 + 0.3 x is -0.75 at x = -10 (the rim), the field's minimum over the window.
    EXPECT_EQ(error_of("object:\n  type: window\n  thickness: 4\n  diameter: 20\n  ior: 1.5\n"
                       "  index_field: {type: linear_n2, gradient: [0.3, 0, 0]}\n"),
              "scene.yaml:6:16: object.index_field: n^2 = -0.75 at (-10, 0, -2) mm: the index must be real everywhere "
              "in the object");
}

TEST(SceneGrin, AnAsymmetricHessianIsRefused) {
    EXPECT_EQ(error_of("object:\n  type: lens\n  r1: 50\n  r2: -50\n  center_thickness: 6\n  diameter: 25\n  ior: 1.5\n"
                       "  index_field:\n    type: quadratic_n2\n"
                       "    hessian: [[0.01, 0.002, 0], [0.001, 0.01, 0], [0, 0, 0.01]]\n"),
              "scene.yaml:10:14: object.index_field.hessian: hessian[0][1] = 0.002 but hessian[1][0] = 0.001: a "
              "Hessian is symmetric");
    EXPECT_EQ(error_of("object: {type: window, thickness: 4, diameter: 20, ior: 1.5, index_field: {type: quadratic_n2, "
                       "hessian: [[1, 0], [0, 1]]}}\n"),
              "scene.yaml:1:105: object.index_field.hessian: expected a list of 3 rows of 3 numbers [[..], [..], [..]], "
              "got a list of 2 items");
}

TEST(SceneGrin, AnInhomogeneityThatMissesTheGlassIsRefused) {
    EXPECT_EQ(error_of(kWindow + "defects:\n  - {type: inhomogeneity, center: [0, 0, 9], radius: 1, delta_n: 0.01}\n"),
              "scene.yaml:3:35: defects[0].center: the inhomogeneity at (0, 0, 9) does not meet the glass (its centre is "
              "7 mm outside, beyond its radius)");
}

TEST(SceneGrin, ZeroDeltaNIsRefused) {
    EXPECT_EQ(error_of(kWindow + "defects:\n  - {type: inhomogeneity, center: [0, 0, 0], radius: 1, delta_n: 0}\n"),
              "scene.yaml:3:66: defects[0].delta_n: must be non-zero: delta_n = 0 leaves the glass unchanged (remove the "
              "defect instead)");
    EXPECT_EQ(error_of(kWindow + "defects:\n  - {type: inhomogeneity, center: [0, 0, 0], radius: 1, delta_n: -0.6}\n"),
              "scene.yaml:3:66: defects[0].delta_n: makes n = 1.5 + (-0.6) = 0.9 < 1 at the inhomogeneity's centre");
}

TEST(SceneGrin, AnIndexFieldWhereItCannotGoIsRefused) {
    // On a defect: the field belongs to the object.
    EXPECT_EQ(error_of(kWindow + "defects:\n  - {type: bubble, center: [0, 0, 0], radius: 0.1, index_field: {type: "
                                 "linear_n2, gradient: [0, 0, 0.1]}}\n"),
              "scene.yaml:3:52: defects[0].index_field: unknown key 'index_field' for a bubble: index_field is a key of the "
              "object (the glass's index as a field); a defect changes the index locally as type inhomogeneity with "
              "delta_n; valid keys are: type, center, radius, semi_axes, rotation, surface_breaking");
    // Graded glass with a local inhomogeneity, or with a defect that cuts a face.
    const std::string graded = "object: {type: window, thickness: 4, diameter: 20, ior: 1.5, index_field: {type: radial_n2, g: 0.01}}\n";
    EXPECT_EQ(error_of(graded + "defects:\n  - {type: inhomogeneity, center: [0, 0, 0], radius: 1, delta_n: 0.01}\n"),
              "scene.yaml:3:12: defects[0].type: an inhomogeneity needs a homogeneous glass around it, but the object has "
              "an index field (radial_n2); give the glass a constant ior");
    EXPECT_EQ(error_of(graded + "defects:\n  - {type: scratch, surface: front, start: [-1, 0], end: [1, 0], width: 0.05, "
                                "depth: 0.02}\n"),
              "scene.yaml:3:12: defects[0].type: a scratch cuts a face, which a graded-index object (radial_n2) cannot "
              "have: its curved paths are traced against the object's own faces and enclosed defects only");
    // A parameter of another field kind.
    EXPECT_EQ(error_of("object: {type: window, thickness: 4, diameter: 20, ior: 1.5, index_field: {type: radial_n2, "
                       "gradient: [0,0,1]}}\n"),
              "scene.yaml:1:93: object.index_field.gradient: unknown key 'gradient' for an index field of type radial_n2; "
              "valid keys are: type, g");
}

TEST(SceneGrin, PlacementRulesOfInhomogeneities) {
    EXPECT_EQ(error_of(kWindow + "defects:\n  - {type: inhomogeneity, center: [0, 0, 1.5], radius: 1, delta_n: 0.01, "
                                 "profile: uniform}\n"),
              "scene.yaml:3:35: defects[0].center: the uniform inhomogeneity at (0, 0, 1.5) is not strictly inside the "
              "glass (it reaches 0.5 mm beyond the back face): a sharp inclusion must be enclosed; use profile: smooth to "
              "clip it to the glass");
    // A smooth one may reach beyond a face: it is clipped.
    EXPECT_EQ(error_of(kWindow + "defects:\n  - {type: inhomogeneity, center: [0, 0, 1.5], radius: 1, delta_n: 0.01}\n"),
              "(parsed without error)");
    EXPECT_EQ(error_of(kWindow + "defects:\n  - {type: bubble, center: [0, 0, 0], radius: 0.5}\n"
                                 "  - {type: inhomogeneity, center: [0.5, 0, 0], radius: 1, delta_n: 0.01}\n"),
              "scene.yaml:4:35: defects[1].center: this inhomogeneity overlaps defects[0] (a bubble): their bounding boxes "
              "intersect, and an inhomogeneity may overlap no other defect");
    EXPECT_EQ(error_of(kWindow + "defects:\n  - {type: inhomogeneity, center: [0, 0, 0], radius: 1, delta_n: 0.01, "
                                 "profile: smoth}\n"),
              "scene.yaml:3:81: defects[0].profile: expected smooth or uniform, got 'smoth' (did you mean 'smooth'?)");
}

TEST(SceneGrin, SphereKeys) {
    EXPECT_EQ(error_of("object: {type: sphere, radius: 5, ior: 1.5, rim: absorbing}\n"),
              "scene.yaml:1:45: object.rim: unknown key 'rim' for a sphere: a sphere has no rim; valid keys are: type, "
              "radius, ior, absorption, index_field");
    EXPECT_EQ(error_of("object: {type: sphere, radius: -5, ior: 1.5}\n"),
              "scene.yaml:1:32: object.radius: must be a positive finite length (got -5)");
    EXPECT_EQ(error_of("object: {type: sphere, radius: 5, diameter: 10, ior: 1.5}\n"),
              "scene.yaml:1:35: object.diameter: unknown key 'diameter' for a sphere: a sphere is given by its radius "
              "alone; valid keys are: type, radius, ior, absorption, index_field");
}

TEST(SceneGrin, FieldTypeAndToleranceValues) {
    EXPECT_EQ(error_of("object: {type: window, thickness: 4, diameter: 20, ior: 1.5, index_field: {type: cubic_n2}}\n"),
              "scene.yaml:1:82: object.index_field.type: expected linear_n2, radial_n2, spherical_n2, quadratic_n2 or "
              "linear_n, got 'cubic_n2'");
    EXPECT_EQ(error_of(kWindow + "mesh: {index_tolerance: 0}\n"),
              "scene.yaml:2:25: mesh.index_tolerance: must be in (0, 0.1] (a tolerance on n^2), got 0");
}

}  // namespace
}  // namespace ltm
