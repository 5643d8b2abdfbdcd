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
