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

}  // namespace ltm::test
