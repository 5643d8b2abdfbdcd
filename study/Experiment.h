#pragma once
// An experiment (the paper's Fig. 3 and its like): the scenes an experiment.yaml lists, rendered
// through the same pipeline as `render` (study/SceneRun.h), with numbers on every defect in every
// image: the contrast-to-noise ratio against the defect-free surround of the same scene, the
// false positives of the defect-free reference scene, and the best new feature.
//
// experiment.yaml (strict, scene/StrictYaml.h):
//   scenes:          [{file: a.yaml, label: "r = 0.5"}, ...]   the montage's columns, in order
//   reference:       the defect-free scene (its false positives are counted)
//   montage:         [BrightField, ScatterCount, ...]           the montage's rows
//   candidates:      [ScatterDiameter, ...]                     new features competing for the last row
//   defect_fraction: 0.05                                       optional, see below
//
// Regions. A defect's image is traced, not projected: the pixels at least `defect_fraction` of
// whose paths meet the defect before any other (study/GroundTruth.h, the dataset's ground truth
// at a lower threshold, since CNR wants every pixel the defect visibly changes). Its surround is
// geometric: the camera pixels whose centre ray through the defect-free object passes between
// 2 r + 2 px and 5 r + 4 px beyond the defect's ellipsoid (r its smallest semi-axis, px a pixel's
// width), minus every pixel any path of which met any defect. Pixels outside 0.95 of the clear
// aperture are left out (the rim's own image is no defect).
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "defects/SolidBuilder.h"
#include "features/Contrast.h"
#include "io/Image.h"
#include "io/Json.h"
#include "scene/Scene.h"
#include "study/SceneRun.h"

namespace ltm {

inline constexpr double kExperimentDefectFraction = 0.05;

struct ExperimentSpec {
    std::string file, folder;
    std::vector<std::pair<std::string, std::string>> scenes;  // file (relative to folder), label
    std::string reference;
    std::vector<std::string> montage, candidates;
    double defect_fraction = kExperimentDefectFraction;
};

// Throws InputError (located) on bad input.
ExperimentSpec load_experiment(const std::string& path);

struct ExperimentScene {
    std::string file, label, stem;   // file as listed; stem names its output folder
    Scene scene;
    Solid solid;
    SceneRun run;
};

// Loads every scene and builds its solid once (surfaces only where no defect cuts the glass), so
// that a bad scene stops the experiment before anything is rendered. Throws InputError (the
// scene's own located error) or std::invalid_argument / TetGenError naming the scene file.
std::vector<ExperimentScene> load_experiment_scenes(const ExperimentSpec& spec);

// Renders one scene (as `ltmsim render` does, reference included).
// The scenes share `cache` (study/ReferenceCache.h): each pixel's defect-free reference is
// rendered once for the experiment.
void render_experiment_scene(ExperimentScene& s, int threads, ReferenceCache* cache = nullptr);

// The regions the contrast table measures for each defect of a rendered scene (see above; none for
// a defect-free scene). `ltmsim experiment` writes them as OUT/<scene>/regions.json
// (regions_json) so that later measurements of the same scene (`ltmsim acquire`) judge the very
// same pixels: {"defects": [{"defect": k, "radius_mm": r, "defect_pixels": [k, ...],
// "surround_pixels": [k, ...]}, ...]}, camera pixel indices k = m N + n.
struct DefectRegions {
    int defect = 0;
    double radius_mm = 0;  // the defect's largest semi-axis
    Region defect_pixels, surround;
};
std::vector<DefectRegions> experiment_regions(const ExperimentSpec& spec, const ExperimentScene& scene);
io::Json regions_json(const std::vector<DefectRegions>& regions);
// Reads regions_json's file; InputError naming the file and the bad entry (an index outside
// [0, pixels) among them).
std::vector<DefectRegions> read_regions_json(const std::string& path, long pixels);

struct ExperimentResult {
    std::string csv, markdown, best;
    Image montage;
    std::vector<std::vector<DefectRegions>> regions;  // per scene, in the spec's order
};

// The numbers, the regions they were measured in, and the montage, from the rendered scenes.
ExperimentResult evaluate_experiment(const ExperimentSpec& spec, const std::vector<ExperimentScene>& scenes);

// The defect's traced image (see above) and the pixels some path of which met any defect.
Region traced_defect_region(const Scene& scene, const RenderResult& render, int defect, double min_fraction);
Region pixels_meeting_defects(const RenderResult& render);

}  // namespace ltm
