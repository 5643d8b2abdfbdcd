#include "scene/SceneSolid.h"

#include "scene/SceneLoader.h"

namespace ltm {

Solid build_solid(const Scene& scene, StageReport* report, bool surfaces_only) {
    try {
        return build_solid(Lens(scene.object.lens), scene.defects, scene.mesh, report, scene.object.index_field,
                           surfaces_only);
    } catch (const DefectError& e) {
        throw scene_error(scene, e.key_path(), e.message);
    }
}

}  // namespace ltm
