#pragma once
// An experiment (the paper's Fig. 3 and its like): the scenes an experiment.yaml lists, rendered
// through the same pipeline as `render` (study/SceneRun.h), with numbers on every defect in every
// image: the contrast-to-noise ratio against the defect-free surround of the same scene, in the
// rendered image and, when the caller measures the scenes (MeasuredImages: `ltmsim experiment`
// does, through acquire/), in the image an instrument would measure; the false positives of the
// defect-free reference scene; and the best new feature. The file format: docs/experiment.md.
//
// experiment.yaml (strict, scene/StrictYaml.h):
//   scenes:          [{file: a.yaml, label: "r = 0.5"}, ...]   the montage's columns, in order
//   reference:       the defect-free scene (its false positives are counted)
//   montage:         [BrightField, ScatterCount, ...]           the montage's rows
//   candidates:      [ScatterDiameter, ...]                     optional: new features competing for the last row
//   defect_fraction: 0.05                                       optional, see below
//
// Regions. A defect's image is traced, not projected: the pixels at least `defect_fraction` of
// whose paths meet the defect before any other (study/GroundTruth.h, the dataset's ground truth
// at a lower threshold, since CNR wants every pixel the defect visibly changes). Its surround is
// geometric: the camera pixels whose centre ray through the defect-free object passes between
// 2 r + 2 px and 5 r + 4 px beyond the defect (px a pixel's width): beyond its ellipsoid, r its
// smallest semi-axis, for a bubble, particle or inhomogeneity; beyond the tube of radius
// hypot(w / 2, depth) around a scratch's centre line (it holds the scratch's cross-section), r the
// smaller of its half-width w / 2 and depth. Every pixel any path of
// which met any defect is removed from it. Pixels outside 0.95 of the clear aperture are left out
// of both (the rim's own image is no defect).
//
// Noise. A CNR's noise is the surround's standard deviation, never less than the image's
// resolution q / sqrt 12 (features/Contrast.h): for a rendered image q is one sample's share,
// 1 / S of a pixel's light (S samples per pixel), the display pitch / S of a mean position and
// 1 / S display pixels of an ellipse width, and 1 for counts, display indices, extents between
// display pixel centres and angles in degrees.
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "defects/SolidBuilder.h"
#include "features/Contrast.h"
#include "features/Plot.h"
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
    std::vector<std::string> montage, candidates;  // candidates may be empty
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
// same pixels: {"defects": [{"defect": k, "kind": "bubble", "size": {"semi_axis_a_mm": a, ...},
// "defect_pixels": [k, ...], "surround_pixels": [k, ...]}, ...]}, camera pixel indices k = m N + n.
struct DefectRegions {
    int defect = 0;
    std::string kind;                                  // to_string(DefectType)
    std::vector<std::pair<std::string, double>> size;  // defect_size
    Region defect_pixels, surround;
    // "bubble r = 0.0997 mm", "scratch 0.05 x 0.02 mm, 4 mm long": for labels.
    std::string describe() const;
    // {"semi_axis_a_mm": a, ...}: the size as regions.json and acquire's report give it.
    io::Json size_json() const;
};
// A defect's size as contrast.csv and regions.json give it, in mm, by kind: semi_axis_a_mm,
// semi_axis_b_mm, semi_axis_c_mm for the ellipsoids (bubble, particle, inhomogeneity; all three
// the radius for a sphere); width_mm, depth_mm and length_mm (along its path on the face) for a
// scratch.
std::vector<std::pair<std::string, double>> defect_size(const Scene& scene, const Defect& d);
// Every size column defect_size can give, in contrast.csv's order.
const std::vector<std::string>& defect_size_columns();
std::vector<DefectRegions> experiment_regions(const ExperimentSpec& spec, const ExperimentScene& scene);
io::Json regions_json(const std::vector<DefectRegions>& regions);
// Reads regions_json's file; InputError naming the file and the bad entry (an index outside
// [0, pixels) among them).
std::vector<DefectRegions> read_regions_json(const std::string& path, long pixels);

// A scene's feature images as an instrument measures them: what the caller (`ltmsim experiment`,
// through acquire/) hands in; study/ does not know how they were made.
struct MeasuredImages {
    FeatureImages features;                   // the channels measured, features.exr's names
    std::map<std::string, std::string> how;   // channel -> how it was measured ("gray, K = 42")
    std::map<std::string, double> resolution; // channel -> the step q its values resolve
};
struct Measurement {
    std::string instrument;              // one sentence for contrast.md: the sensor and display
    std::vector<MeasuredImages> scenes;  // per scene, in the spec's order
};

struct ExperimentResult {
    std::string csv, markdown;
    std::string false_positives_csv;  // per channel, in the reference scene
    std::string best;       // the best new feature ("" without candidates)
    std::string headline;   // one sentence on it (contrast.md's first line after the title)
    Image montage;
    std::vector<std::vector<DefectRegions>> regions;  // per scene, in the spec's order
};

// The numbers, the regions they were measured in, and the montage, from the rendered scenes, and
// from their measured images when `measured` is given (one per scene). The best new feature is,
// among the candidates whose weakest CNR over the smallest defects reaches 5 (the Rose criterion:
// each of them visible), the one with the fewest false positives in the reference scene, then the
// largest weakest CNR; if no candidate reaches 5, the one with the largest weakest CNR. It is
// judged on the measured images when there are any, else on the rendered ones.
ExperimentResult evaluate_experiment(const ExperimentSpec& spec, const std::vector<ExperimentScene>& scenes,
                                     const Measurement* measured = nullptr);

// The resolution of a rendered image (see "Noise" above): S samples per pixel on `display`.
Resolution rendered_resolution(int samples_per_pixel, const DisplayGrid& display);
Resolution rendered_resolution(const Scene& scene);

// One image's CNR of one defect in its regions (contrast_to_noise with the image's resolution):
// none (cnr NaN) when the defect has no finite pixel in the image or its surround fewer than 2 (a
// decoder's NaN rows); 0 for a defect with no traced pixel within the regions' aperture (no
// image). Means, spread and noise are NaN where they were not measured.
ContrastResult measure_cnr(const std::vector<float>& image, const DefectRegions& g, double resolution);

// The defect's traced image (see above) and the pixels some path of which met any defect.
Region traced_defect_region(const Scene& scene, const RenderResult& render, int defect, double min_fraction);
Region pixels_meeting_defects(const RenderResult& render);

}  // namespace ltm
