// A scene and its solid from YAML text, for tests that trace or validate a scene written inline:
// parse_scene (scene/SceneLoader.h) and then build_solid (scene/SceneSolid.h) of the scene's
// object, index field, defects and mesh options, as `ltmsim` does for a scene file.
#pragma once

#include <string>

#include "defects/SolidBuilder.h"
#include "geometry/Lens.h"
#include "scene/Scene.h"
#include "scene/SceneLoader.h"
#include "scene/SceneSolid.h"

namespace ltm::test {

struct Built {
    Scene scene;
    Solid solid;
};

// Parses `yaml` (messages name it `file_name`) and builds its solid. Throws what parse_scene and
// build_solid throw.
inline Built build(const std::string& yaml, const std::string& file_name = "test.yaml") {
    Built b;
    b.scene = parse_scene(yaml, file_name);
    b.solid = build_solid(b.scene);
    return b;
}

// A small smooth inclusion in a window, meshed coarsely (a fast TetGen stage, a few thousand
// tetrahedra), and a small camera: for the commands that mesh, write or trace such a region.
inline const char* const kSmallSmoothInclusion = R"(
object: {type: window, thickness: 4.0, diameter: 12.0, ior: 1.5}
defects:
  - {type: inhomogeneity, center: [0.0, 0.0, 0.0], radius: 1.5, delta_n: 0.02, profile: smooth}
camera: {resolution: [24, 24], size: [6.0, 6.0], numerical_aperture: 0.002, samples_per_pixel: 4}
display: {resolution: [100, 100], size: [50.0, 50.0], z: 40.0}
mesh: {index_tolerance: 2e-3}
)";

// A window with a V scratch on its front face: the glass is a Boolean result, its first segments
// meet the scratch's walls (which support nothing: the mesh lies on both sides of them).
inline const char* const kScratchedWindow = R"(
object: {type: window, thickness: 5.0, diameter: 20.0, ior: 1.5}
defects:
  - {type: scratch, surface: front, profile: V, width: 0.4, depth: 0.2, start: [-4.0, -1.0], end: [4.0, 1.5]}
camera: {resolution: [8, 8], size: [10.0, 10.0], numerical_aperture: 0.02, samples_per_pixel: 16}
display: {resolution: [30, 30], size: [40.0, 40.0], z: 30.0}
seed: 4
)";

}  // namespace ltm::test
