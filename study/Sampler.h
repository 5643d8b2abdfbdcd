#pragma once
// Sample i of a dataset: its scene, drawn from the spec (study/DatasetSpec.h) with random numbers
// that depend on (spec, i) alone.
//
// Seeds. The sample's seed is mix_seed(spec.seed, i) (trace/Rng.h); it is the seed of its scene
// file (so `ltmsim render scene.yaml` reproduces the sample), and the streams
// Rng(sample seed, kSamplingStream + j) draw its parameters, apart from the render's streams
// Rng(seed, pixel, sample) (a pixel index never reaches 2^62).
//
// Draws, in this order (docs/dataset.md, "How a sample is drawn"):
//  1. defect-free with probability defect_free_fraction, and its split, each from its own stream;
//  2. the object, when the spec varies it: every varied key drawn, redrawn until Lens::problems
//     accepts the object;
//  3. the counts of every kind, redrawn until the total is 1..kMaxDefectsPerSample (a sample that
//     is not defect-free has a defect);
//  4. the defects, kind by kind in spec order: parameters, then position (uniform over the glass;
//     pits and scratches uniform over the area of their face), orientation (uniform rotations for
//     ellipsoids given by semi_axes; a uniform direction for straight scratches, a uniform start
//     angle for arcs), each redrawn until the scene loader's placement rules accept it and it
//     keeps clear of the enclosed defects drawn before it (bounding spheres apart, so that
//     enclosed defects need no Boolean).
// A redraw loop that reaches spec.max_attempts means the spec cannot be met: InputError at the
// spec's entry ("defects[1]: cannot place ... after 1000 draws (sample 17): <last reason>").
// The scene is written with scene_to_yaml and read back with the strict loader, and the scene
// read back is the one rendered: what scene.yaml says is what was rendered.
#include <cstdint>
#include <string>
#include <vector>

#include "scene/Scene.h"
#include "study/DatasetSpec.h"

namespace ltm {

inline constexpr std::uint64_t kSamplingStream = std::uint64_t{1} << 62;

struct SampleDraw {
    long index = 0;
    std::uint64_t seed = 0;
    std::string split;
    bool defect_free = false;
    Scene scene;                 // as read back from scene_yaml
    std::string scene_yaml;      // samples/<i>/scene.yaml
    std::vector<int> kinds;      // per defect: its entry in spec.defects
};

// The folder name of sample i: six digits, more when needed ("000017", "1234567").
std::string sample_name(long index);

SampleDraw draw_sample(const DatasetSpec& spec, long index);

}  // namespace ltm
