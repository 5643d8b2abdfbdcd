#pragma once
// One scene through the whole pipeline, the same way for `render`, `experiment` and `dataset`:
// the tracer, the light transport matrix with per-defect path counts (the ground truth), the
// defect-free reference of the deflection map, and the feature images.
//
// The reference. The deflection map is the mean display position of each camera pixel minus that
// of the defect-free object. Both are rendered with the same random numbers, so a pixel none of
// whose paths met a defect traces exactly the paths of the defect-free object: its reference is
// its own mean and its deflection exactly 0. Only the pixels some path of which met a defect are
// rendered again without the defects (RenderOptions::pixels), which makes the reference cost in
// proportion to the defects' images instead of a second full render.
#include <string>
#include <vector>

#include "defects/SolidBuilder.h"
#include "features/Features.h"
#include "geometry/StageReport.h"
#include "study/ReferenceCache.h"
#include "scene/Scene.h"
#include "trace/Render.h"
#include "trace/Tracer.h"

namespace ltm {

struct SceneRunOptions {
    Representation representation = Representation::Analytic;  // see auto_representation
    bool robust = true;                                         // TracerOptions::robust
    int threads = 0;                                            // RenderOptions::threads
    bool progress = false;
    // dark_block < 0: automatic, 60 display pixels or the display's smaller side if less.
    FeatureOptions features{0.0, 0.99, -1};
    // Shared by scenes with the same object (study/ReferenceCache.h): each pixel's reference is
    // rendered once for all of them. A defect-free scene run through it gives every pixel's.
    ReferenceCache* reference_cache = nullptr;
};

struct SceneRun {
    Representation representation = Representation::Analytic;
    RenderResult render;             // T, path statistics, defect_paths
    std::vector<float> reference;    // MeanX, MeanY of the defect-free object, 2 per camera pixel
    FeatureImages features;          // with Deflection* (exactly 0 for a defect-free scene)
    long reference_pixels = 0;       // pixels rendered again without the defects
    long reference_reused = 0;       // pixels whose reference came from the cache
};

// Analytic where no defect cuts the glass (no mesh needed), else Refined.
Representation auto_representation(const Solid& solid);

// The display geometry features need.
DisplayGrid display_grid(const Scene& scene);

// A negative dark_block resolved: min(60, P, Q).
FeatureOptions resolved_feature_options(const Scene& scene, FeatureOptions options);

// The whole pipeline; stages "trace-setup", "render", "reference", "features" go to `report`.
SceneRun run_scene(const Scene& scene, const Solid& solid, const SceneRunOptions& options, StageReport* report);

// The reference for `own`, a render of `scene` with track_defects (see above). A defect-free
// scene is its own reference. `own_means`: own's MeanX and MeanY channels.
std::vector<float> defect_free_reference(const Scene& scene, const RenderResult& own, const std::vector<float>& own_mean_x,
                                         const std::vector<float>& own_mean_y, Representation representation,
                                         const RenderOptions& options, long* rendered_pixels = nullptr,
                                         ReferenceCache* cache = nullptr, long* reused_pixels = nullptr);

// The representation the reference is rendered in: the object without defects needs no mesh, so
// Analytic, except that a mesh-only render keeps its own (its facets are what it measures).
Representation reference_representation(Representation scene_representation);

}  // namespace ltm
