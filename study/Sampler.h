#pragma once
// Sample i of a dataset: its scene, drawn from the spec (study/DatasetSpec.h) with random numbers
// that depend on (spec, i) alone.
//
// Seeds. The sample's seed is mix_seed(spec.seed, i) (trace/Rng.h); it is the seed of its scene
// file (so `ltmsim render scene.yaml` reproduces the sample), and the streams
// Rng(sample seed, kSamplingStream + j) draw its parameters, apart from the render's streams
// Rng(seed, pixel, sample) (a pixel index never reaches 2^62).
//
// Draws, in this order (docs/dataset.md, "How a sample is drawn"), each from its own stream:
//  1. defect-free with probability defect_free_fraction (stream +0), and its split (+1);
//  2. the object, when the spec varies it (+2): every varied key drawn, all redrawn until
//     Lens::problems accepts the object;
//  3. the counts of every kind (+3), redrawn until the total is 1..kMaxDefectsPerSample (a sample
//     that is not defect-free has a defect);
//  4. the parameters of every defect, kind by kind in spec order (kParameterStream): everything
//     the spec gives a value or a distribution for (sizes, delta_n, the face, the profile, ...),
//     each drawn once. A normal is truncated to its key's range (drawn again, from this stream,
//     until the value is in it). Nothing about where a defect goes touches this stream, so the
//     sizes are exactly the draws of the requested laws, whatever fits where;
//  5. the positions (kPlacementStream): position (uniform over the glass; pits and scratches
//     uniform over the area of their face) and orientation (uniform rotations for ellipsoids
//     given by semi_axes; a uniform direction for straight scratches, a uniform start angle for
//     arcs), defect by defect, each redrawn (up to max_attempts times) until the scene loader's
//     placement rules accept it and it keeps clear of the enclosed defects placed before it
//     (bounding spheres apart, so that enclosed defects need no Boolean). Given the sizes, each
//     defect's position is uniform over the room the ones before it left.
//
// A defect that finds no room: if it finds none in an empty object either (max_attempts more
// positions), its size fits nowhere: InputError at the key that decides its size
// ("defects[0].radius: a bubble with radius 0.52 (sample 17) fits nowhere in the object ...").
// Otherwise the earlier defects crowd it out, and every position of the sample is drawn again,
// sizes kept, up to kPlacementRounds rounds; then InputError at its entry naming the sample and
// every size ("defects[1]: sample 17: its 12 defects do not fit together ..."). A truncated normal
// with no value in its range in max_attempts draws, or an arc whose length closes its circle, is
// an InputError at its key too.
// The scene's seed is mix_seed(spec seed, index); its reference_seed is the spec's seed (unless
// the spec's scene gives one), so that every sample of one object is measured against one golden
// reference (study/SceneRun.h). The scene is written with scene_to_yaml and read back with the
// strict loader, and the scene read back is the one rendered: what scene.yaml says is what was
// rendered.
#include <cstdint>
#include <string>
#include <vector>

#include "io/Json.h"
#include "scene/Scene.h"
#include "study/DatasetSpec.h"

namespace ltm {

inline constexpr std::uint64_t kSamplingStream = std::uint64_t{1} << 62;
inline constexpr std::uint64_t kParameterStream = kSamplingStream + 4;
inline constexpr std::uint64_t kPlacementStream = kSamplingStream + 5;
// Rounds of placing all of a sample's defects before they are declared not to fit together. A
// round that fails costs up to max_attempts positions of the defect that found no room; a sample
// whose defects fit together in one round in q of the tries fails all rounds with (1 - q)^100.
inline constexpr int kPlacementRounds = 100;

struct SampleDraw {
    long index = 0;
    std::uint64_t seed = 0;
    std::string split;
    bool defect_free = false;
    Scene scene;                 // as read back from scene_yaml
    std::string scene_yaml;      // samples/<i>/scene.yaml
    std::vector<int> kinds;      // per defect: its entry in spec.defects
    // Per defect, the value every key of its spec entry drew, by the spec's key names: numbers
    // ({"radius": 0.2}, {"semi_axes": [a, b, c]}, {"length": 3.1}) and words ({"surface": "front"}).
    std::vector<io::Json> sampled;
    io::Json object_sampled = io::Json::object();  // the object's varied keys and their values
    int placement_rounds = 0;    // rounds of step 5 (1 unless crowding made it start again)
};

// The keys of a spec entry that draw_sample draws for each of its defects (step 4), in its order,
// with their laws: a number's or a word's. "semi_axes" is three keys, "semi_axes[0]" to
// "semi_axes[2]"; "arc_radius" is drawn for arcs only. The dataset card lists them.
struct SampledKey {
    std::string key;
    const Distribution* number = nullptr;  // or
    const Choice* word = nullptr;
};
std::vector<SampledKey> sampled_keys(const DefectKindSpec& k);

// The object's keys that the spec varies (step 2), in the order they are drawn, by the names the
// base object's type gives them (a window's "thickness", a lens's "center_thickness", ...).
std::vector<std::pair<std::string, const Distribution*>> varied_object_keys(const DatasetSpec& spec);

// The folder name of sample i: six digits, more when needed ("000017", "1234567").
std::string sample_name(long index);

SampleDraw draw_sample(const DatasetSpec& spec, long index);

}  // namespace ltm
