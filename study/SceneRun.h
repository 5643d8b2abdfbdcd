#pragma once
// One scene through the whole pipeline, the same way for `render`, `experiment` and `dataset`:
// the tracer, the light transport matrix with per-defect path counts (the ground truth), the
// defect-free reference of the deflection map, and the feature images.
//
// The reference. The deflection map is the mean display position of each camera pixel minus that
// of the defect-free object (docs/features.md). An instrument measures that reference separately,
// on a golden sample, and its measurement carries noise of its own. So does this one: the same
// scene without its defects is rendered at every pixel with random numbers of its own, the seed
// reference_seed (mix_seed of the scene's render seed, or of its `reference_seed` where it gives
// one, and kReferenceStream, trace/Rng.h), which no render of the scene itself uses. Away from the defects the deflection map therefore shows the
// difference of two independent Monte Carlo estimates of the same means (its noise is sqrt 2
// times one render's), as the difference of two measurements would. Scenes of one object that
// give one `reference_seed` (a dataset's samples) share one reference, as the parts of a product
// are measured against one golden sample. The seed depends on the scene's seeds (and
// RenderOptions::stream) only, so the reference, and every deflection, is
// bit-identical for any thread count. It costs one more render of the defect-free object (in the
// analytic representation, whatever the scene's), whose rows are reduced to their means as they
// pass (a RowSink), so it never holds that object's T.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "defects/SolidBuilder.h"
#include "features/Features.h"
#include "geometry/StageReport.h"
#include "io/LtmFile.h"
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
    // Shared by scenes with the same object, camera, display and seed (study/ReferenceCache.h):
    // the reference is rendered once for all of them.
    ReferenceCache* reference_cache = nullptr;
    // Streaming (`render --max-memory`): when T's arrays would exceed max_matrix_bytes (> 0), its
    // rows go to an io::LtmFileStream for `stream_path` (the ltm.npz to be; its folder is created
    // if missing) instead of SceneRun::render.T, and the features are computed from the same row
    // blocks as they pass (every feature is a function of its own row, so the images are the
    // ones the whole T gives, bit for bit). The caller commits SceneRun::streamed_T.
    std::size_t max_matrix_bytes = 0;
    std::string stream_path;
    // Measure the render stage's own peak RSS (io/PeakRss.h: resets the process's high-water
    // mark, so only where no other render runs at the same time: `render`, not `dataset`).
    bool measure_memory = false;
};

// The render stage's memory (SceneRunOptions::measure_memory).
struct RenderMemory {
    bool measured = false;
    std::uint64_t peak_rss_bytes = 0;   // the largest RSS during the render stage
    std::uint64_t start_rss_bytes = 0;  // RSS when it began (what the process held already)
    bool per_run = false;               // the peak is the stage's own (io::PeakRssMeter::per_run)
    std::string method;                 // io::PeakRssMeter::method
};

struct SceneRun {
    Representation representation = Representation::Analytic;
    RenderResult render;             // T, path statistics, defect_paths
    std::vector<float> reference;    // MeanX, MeanY of the defect-free object, 2 per camera pixel
    FeatureImages features;          // with Deflection* (exactly 0 for a defect-free scene)
    long reference_pixels = 0;       // pixels of the reference rendered by this run (all, or 0 if cached)
    long reference_reused = 0;       // pixels whose reference came from the cache
    // render.streamed: T's rows, spilled beside stream_path, waiting for commit() (the archive).
    std::shared_ptr<LtmFileStream> streamed_T;
    RenderMemory render_memory;
};

// Analytic where no defect cuts the glass (no mesh needed), else Refined.
Representation auto_representation(const Solid& solid);

// The display geometry features need.
DisplayGrid display_grid(const Scene& scene);

// A negative dark_block resolved: min(60, P, Q).
FeatureOptions resolved_feature_options(const Scene& scene, FeatureOptions options);

// The whole pipeline; stages "trace-setup", "render", "reference", "features" go to `report`.
SceneRun run_scene(const Scene& scene, const Solid& solid, const SceneRunOptions& options, StageReport* report);

// The seed of the reference's random numbers for a render of `scene` with `options` (see above).
inline constexpr std::uint64_t kReferenceStream = 0x7265666572656e63ull;  // "referenc"
std::uint64_t reference_seed(const Scene& scene, const RenderOptions& options);

// The reference for a render of `scene` with `options` (see above): MeanX, MeanY of the defect-free
// object, 2 per camera pixel (NaN where its row is empty), rendered in `representation`'s
// reference_representation with reference_seed. With a cache, a reference another scene of the
// same key rendered is taken from it (rendered_pixels 0, reused_pixels all), else rendered and
// stored (rendered_pixels all).
std::vector<float> defect_free_reference(const Scene& scene, Representation representation, const RenderOptions& options,
                                         long* rendered_pixels = nullptr, ReferenceCache* cache = nullptr,
                                         long* reused_pixels = nullptr);

// The representation the reference is rendered in: the object without defects needs no mesh, so
// Analytic, except that a mesh-only render keeps its own (its facets are what it measures).
Representation reference_representation(Representation scene_representation);

}  // namespace ltm
