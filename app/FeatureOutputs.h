#pragma once
// The feature images of a light transport matrix, written next to it: DIR/features.exr (one
// FLOAT channel per feature and conventional image) and DIR/features/<Channel>.png (pseudo
// colour with a colour bar). Shared by `render`, `features` and `experiment`.
#include <optional>
#include <string>
#include <vector>

#include "features/Features.h"
#include "features/Plot.h"
#include "scene/Scene.h"
#include "io/CsrMatrix.h"
#include "io/Json.h"
#include "geometry/StageReport.h"
#include "study/SceneRun.h"
#include "trace/Render.h"

namespace ltm::app {

// The geometry features need, as recorded in DIR/run.json.
struct RenderGeometry {
    int camera_columns = 0, camera_rows = 0;
    ImageExtent camera;  // the camera's field of view (scene.camera.size), for the previews' axes
    DisplayGrid display;
    int samples_per_pixel = 0;  // scene.camera.samples_per_pixel; 0 where run.json does not say
};

RenderGeometry render_geometry(const Scene& scene);

// The files write_render_folder writes into its folder (beside the previews' folder features/).
std::vector<const char*> render_folder_files();

// DIR/run.json: the resolved scene, seed, version, representation, estimator ({"estimator":
// "split", "split_depth": 4} or {"estimator": "sample"}), timings and path statistics;
// `result` is a JSON object describing what was rendered; `memory`, when not null, is recorded
// under "memory" (memory_json).
void write_run_json(const std::string& dir, const Scene& scene, const RenderResult& r, Representation representation,
                    int threads, const io::Json& result, const StageReport& report, const io::Json& memory = nullptr);

// run.json's "memory": the render stage's peak RSS (study/SceneRun.h, RenderMemory), T's bytes
// (for rows > 0: T's camera pixels; 8 bytes per nonzero and 8 per row + 1), the budget (`render --max-memory`, bytes; 0 for none) and whether T was streamed, and the
// process's peak RSS so far (getrusage, the whole command up to run.json). docs/cli.md lists the
// keys.
io::Json memory_json(const RenderMemory& m, const RenderResult& r, std::int64_t rows, std::size_t max_matrix_bytes);

// A render folder: DIR/ltm.npz (written from T, or run.streamed_T committed when T was streamed), DIR/reference.exr (the defect-free
// object's MeanX and MeanY, study/SceneRun.h), DIR/features.exr
// and DIR/features.npz with DIR/features/*.png, and DIR/run.json (written last). On failure the
// files this call wrote are removed and the exception rethrown.
// previews = false (render --no-previews) leaves out DIR/features/*.png (and touches nothing
// already in DIR/features/); run.json records "previews".
void write_render_folder(const std::string& dir, const Scene& scene, const SceneRun& run, int threads,
                         StageReport& report, const io::Json& memory = nullptr, bool previews = true);

// Reads the camera and display from DIR/run.json; throws std::runtime_error naming the file.
RenderGeometry read_render_geometry(const std::string& dir);

// Reads DIR/reference.exr (MeanX, MeanY of the defect-free object), if present.
std::optional<std::vector<float>> read_reference(const std::string& dir, int camera_pixels);

// Computes the features and writes them (write_feature_images); returns the images. A negative
// options.dark_block means automatic: 60 display pixels, or the display's smaller side if less.
FeatureImages write_features(const std::string& dir, const CsrMatrix& T, const RenderGeometry& g,
                             const FeatureOptions& options, const std::vector<float>* reference);

// DIR/features.exr (one FLOAT channel per image), DIR/features.npz (the same channels as float32
// arrays of shape (rows, columns), for numpy without an EXR reader) and DIR/features/<name>.png
// (pseudo colour titled with the channel's unit; axes in mm over `camera`, the camera's field of
// view, when it is known); the PNGs only with `previews`. With `group`, every file is committed
// into it (io/AtomicFile.h), in place at its commit; without, each is committed as it is written.
void write_feature_images(const std::string& dir, const FeatureImages& f, const ImageExtent& camera = {},
                          bool previews = true, io::CommitGroup* group = nullptr);

}  // namespace ltm::app
