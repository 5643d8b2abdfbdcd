#pragma once
// What a dataset says about its samples: labels.json per sample, and the COCO annotations of the
// whole dataset built from them (docs/dataset.md, "labels.json", "annotations.json").
#include "io/Json.h"
#include <string>
#include <vector>

#include "features/Features.h"
#include "features/Plot.h"
#include "study/DatasetSpec.h"
#include "study/GroundTruth.h"
#include "study/Sampler.h"
#include "study/SceneRun.h"

namespace ltm {

// The COCO category of each defect kind: stable ids whatever the spec lists.
int coco_category(DefectType kind);

// A defect's physical parameters as its scene file gives them (mm, degrees), plus derived sizes:
// "size" (the largest semi-axis of an ellipsoid, a scratch's width) and, for scratches, "length".
io::Json defect_parameters(const Lens& lens, const Defect& d);

// labels.json of a sample: its index, seed, split, the image size, the ground-truth rule, the
// object (and the values its varied keys drew, `object_sampled`), and per defect its id (the mask
// value), kind, spec entry, parameters, the values its spec keys drew (`sampled`), camera-pixel
// bounding box [x, y, width, height], pixel area, visibility, and its mask as COCO RLE.
std::string sample_labels_json(const DatasetSpec& spec, const SampleDraw& sample, const SceneRun& run,
                               const GroundTruth& truth);

// COCO instance segmentation from the samples' labels.json (parsed, in sample order): one image
// per sample (id = sample index), one annotation per defect with pixels in the mask (RLE, bbox,
// area, category, iscrowd 0, and the physical parameters, visibility and split as attributes).
io::Json coco_annotations(const std::vector<io::Json>& labels);

// previews/<channel>.png (pseudo colour) and previews/mask.png (an 8-bit, colour-coded view of the
// instance mask) of a sample, with axes in mm over `camera` (the camera's field of view).
void write_previews(const std::string& dir, const FeatureImages& features, const GroundTruth& truth,
                    const ImageExtent& camera);

}  // namespace ltm
