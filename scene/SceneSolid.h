#pragma once
// The object solid of a scene: its tagged mesh, surface table and TetGen regions, built from the
// scene's object (with its index field), defects and mesh options (defects/SolidBuilder.h).
#include "defects/SolidBuilder.h"
#include "scene/Scene.h"

namespace ltm {

// `surfaces_only`: no mesh when no defect cuts the glass (defects/SolidBuilder.h).
inline Solid build_solid(const Scene& scene, StageReport* report = nullptr, bool surfaces_only = false) {
    return build_solid(Lens(scene.object.lens), scene.defects, scene.mesh, report, scene.object.index_field,
                       surfaces_only);
}

// The same object without its defects (the reference the deflection map is measured against).
inline Scene defect_free(Scene scene) {
    scene.defects.clear();
    return scene;
}

}  // namespace ltm
