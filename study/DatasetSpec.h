#pragma once
// A dataset spec file (docs/dataset.md): the base scene, how many samples, the seed, and the
// distributions of the defects and of the object. Loaded as strictly as a scene file: every key
// known, every value of the right type and range, errors located "FILE:LINE:COLUMN: key: message"
// (scene/StrictYaml.h); a base scene given by path reports its own located errors.
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "scene/Scene.h"
#include "study/Distribution.h"

namespace ltm {

// Caps (docs/dataset.md, "Limits"): a sample holds at most kMaxDefectsPerSample defects (its
// instance mask and the per-path bookkeeping stay small); a Poisson count's mean is at most
// kMaxPoissonMean (its draws then exceed the cap with probability < 1e-12, and are redrawn).
inline constexpr int kMaxDefectsPerSample = 64;
inline constexpr double kMaxPoissonMean = 16.0;
inline constexpr long kMaxSamples = 100000000;
inline constexpr int kDefaultMaxAttempts = 1000;
// The version of the sampling scheme (study/Sampler.h), part of the canonical spec: 2 draws every
// size once, before and apart from the positions.
inline constexpr int kSamplingScheme = 2;

// Where a spec value sits in the file, for errors found after parsing (an infeasible draw).
struct SpecLocation {
    int line = 0, column = 0;
    std::string key_path;  // e.g. "defects[1].radius"
};

// One entry of `defects`: a kind and the distributions of its parameters.
struct DefectKindSpec {
    DefectType type = DefectType::Bubble;
    CountDistribution count;
    // Bubble, particle, inhomogeneity: a sphere (radius) or an ellipsoid (semi_axes, with a
    // uniformly random orientation).
    std::optional<Distribution> radius;
    std::optional<std::array<Distribution, 3>> semi_axes;
    // Bubble: surface_breaking (a pit) centred on a face, `surface`, its centre at center_depth
    // (mm, along the inward normal) below the face.
    bool surface_breaking = false;
    Distribution center_depth = Distribution::constant(0.0);
    // Inhomogeneity.
    Distribution delta_n = Distribution::constant(0.001);
    Choice index_profile{{"smooth"}};
    // Scratch (and pit): the face; a straight or an arc scratch.
    Choice surface{{"front"}};
    Choice shape{{"straight"}};
    Distribution width = Distribution::constant(0.05), depth = Distribution::constant(0.02);
    Distribution length = Distribution::constant(2.0);  // mm: straight, in the xy-projection; arc: along the arc
    Distribution arc_radius = Distribution::constant(2.0);
    Choice scratch_profile{{"V"}};
    SpecLocation where;  // the entry
    // Where each key the entry gives sits (its value), for errors about what it drew; a key left
    // to its default has none, and such errors point at the entry.
    std::map<std::string, SpecLocation> keys;
    // The location of `key` (e.g. "radius"): its value, or the entry with the key's path.
    SpecLocation location_of(const std::string& key) const;
};

// Object variation: each given key replaces the base scene's value by a draw.
struct ObjectVariation {
    std::optional<Distribution> r1, r2, center_thickness, diameter, radius, ior;
    SpecLocation where;
    bool any() const { return r1 || r2 || center_thickness || diameter || radius || ior; }
};

struct DatasetSplit {
    std::string name;
    double fraction = 1;
};

struct DatasetSpec {
    std::string file;                // the spec's path, for messages
    Scene base;                      // the base scene (its defects are replaced per sample)
    std::string base_source;         // the base scene's file, or "<file> (inline)"
    long samples = 0;
    std::uint64_t seed = 1;
    double defect_free_fraction = 0;
    std::vector<DefectKindSpec> defects;
    SpecLocation defects_where;      // the `defects` list
    ObjectVariation object;
    double mask_fraction = 0.25;     // ground_truth.min_fraction (study/GroundTruth.h)
    std::vector<DatasetSplit> splits{{"train", 1.0}};
    bool keep_ltm = false, previews = false;   // outputs
    // Positions tried per defect and placement round, draws of a truncated normal, object draws,
    // before giving up (study/Sampler.h).
    int max_attempts = kDefaultMaxAttempts;
    // The spec as data, canonical (the resolved base scene as YAML, every default written out):
    // two specs that draw the same samples have the same text. A dataset folder records its hash.
    std::string canonical;
};

// Loads and checks a spec. Throws InputError (scene/StrictYaml.h) on bad input.
DatasetSpec load_dataset_spec(const std::string& path);
DatasetSpec parse_dataset_spec(const std::string& yaml_text, const std::string& file_name);

}  // namespace ltm
