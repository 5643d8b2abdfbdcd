#pragma once
// Where each defect is seen, by tracing: the instance mask and the per-defect labels of a render.
//
// Camera pixel k belongs to defect j when at least `min_fraction` of its sampled paths interact
// with j first (RenderOptions::track_defects, PathResult::defect: the path meets one of the
// defect's surfaces, or passes through a smooth inhomogeneity, before any other defect). A pixel
// that several defects claim goes to the one most of its paths meet (ties: the lower index). The
// fraction is that of paths started, including those a defect absorbs or sends off the display:
// they too are its signal. "First" makes a defect in front hide one behind it, as in any image.
//
// Counting paths instead of projecting shapes is what makes the mask exact where projection
// cannot be: refraction by a curved face moves a defect's image, a scratch is seen through its
// walls, an inhomogeneity's image follows its rays. Where projection is exact (a window at normal
// incidence with a vanishing aperture) the fraction of paths of pixel k meeting a bubble is
// (1 - R0) A_k / A_pixel, A_k the area of the pixel within the bubble's outline and R0 the
// front face's normal-incidence reflectance (reflected paths return to the camera); the tests
// check exactly this (tests/study_ground_truth.cpp).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "scene/Scene.h"
#include "trace/Render.h"

namespace ltm {

// The documented default: a quarter of a pixel's paths (docs/dataset.md, "Ground truth").
inline constexpr double kDefaultMaskFraction = 0.25;

struct DefectLabel {
    int id = 0;                    // 1-based: the mask value, the (id - 1)-th entry of the scene's defects
    DefectType kind = DefectType::Bubble;
    long pixel_area = 0;           // pixels the mask gives this defect
    long footprint = 0;            // pixels at or above the threshold for it, ignoring the others
    std::array<int, 4> bbox{0, 0, 0, 0};  // [x, y, width, height] in camera pixels of its mask pixels (COCO order)
    // pixel_area / footprint: the share of its own image not claimed by another defect; 0 when
    // the defect has no pixel at or above the threshold (too small, outside the view, hidden).
    double visibility = 0;
    double path_pixels = 0;        // sum over pixels of the fraction of paths meeting it (the image's "area" in pixels)
    double max_fraction = 0;       // the largest fraction of any one pixel's paths meeting it
};

struct GroundTruth {
    int width = 0, height = 0;     // camera columns and rows
    double min_fraction = kDefaultMaskFraction;
    std::vector<std::uint16_t> mask;  // width * height, camera pixel order (row 0 at +y); 0: background
    std::vector<DefectLabel> defects;
};

// The mask and labels of a render with track_defects. Throws std::invalid_argument if the render
// did not track its defects, the scene has more than 65535 defects (the mask's range), or
// min_fraction is not in (0, 1].
GroundTruth ground_truth(const Scene& scene, const RenderResult& render, double min_fraction = kDefaultMaskFraction);

}  // namespace ltm
