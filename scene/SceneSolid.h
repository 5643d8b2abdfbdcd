#pragma once
// The object solid of a scene: its tagged mesh, surface table and TetGen regions, built from the
// scene's object (with its index field), defects and mesh options (defects/SolidBuilder.h).
#include "defects/SolidBuilder.h"
#include "scene/Scene.h"

namespace ltm {

// `surfaces_only`: no mesh when no defect cuts the glass (defects/SolidBuilder.h). A defect that
// makes the solid impossible (DefectError: Booleans that leave no glass, a particle not clear of
// everything) is a SceneError located at the defect's key in the scene's file (scene_error), so
// every command reports it as it reports a bad value: one message, exit status 2, nothing written.
Solid build_solid(const Scene& scene, StageReport* report = nullptr, bool surfaces_only = false);

// The same object without its defects (the reference the deflection map is measured against).
inline Scene defect_free(Scene scene) {
    scene.defects.clear();
    return scene;
}

}  // namespace ltm
