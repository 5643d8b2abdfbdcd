#pragma once
// The feature images of a light transport matrix, written next to it: DIR/features.exr (one
// FLOAT channel per feature and conventional image) and DIR/features/<Channel>.png (pseudo
// colour with a colour bar). Shared by `render`, `features` and `experiment`.
#include <optional>
#include <string>
#include <vector>

#include "features/Features.h"
#include "trace/CsrMatrix.h"

namespace ltm::app {

// The geometry features need, as recorded in DIR/run.json.
struct RenderGeometry {
    int camera_columns = 0, camera_rows = 0;
    DisplayGrid display;
};

// Reads the camera and display from DIR/run.json; throws std::runtime_error naming the file.
RenderGeometry read_render_geometry(const std::string& dir);

// Reads DIR/reference.exr (MeanX, MeanY of the defect-free object), if present.
std::optional<std::vector<float>> read_reference(const std::string& dir, int camera_pixels);

// Computes the features and writes features.exr and the PNGs; returns the images. A negative
// options.dark_block means automatic: 60 display pixels, or the display's smaller side if less.
FeatureImages write_features(const std::string& dir, const CsrMatrix& T, const RenderGeometry& g,
                             const FeatureOptions& options, const std::vector<float>* reference);

}  // namespace ltm::app
