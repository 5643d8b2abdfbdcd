#pragma once
// The defect-free reference of the deflection map, computed once per object and shared by every
// scene that has the same object under the same camera, display and random numbers (the scenes
// of an experiment): study/SceneRun.h renders it only if no scene before it did. An experiment
// then measures all its scenes against one reference, as an inspection measures all its parts
// against one golden sample.
//
// Why this never changes a result. The reference is the mean display position of each row of the
// defect-free object's T, rendered with the reference's own seed (study/SceneRun.h,
// reference_seed). It depends on the defect-free scene (object, camera, display, mesh options),
// that seed and the tracer's representation only, so a value computed for one scene is the value
// any other scene with the same key would compute. The key holds all of these (the scene as JSON
// without its defects and without the file it came from); scenes whose key differs share nothing.
// Dataset samples have seeds of their own but one reference_seed (the spec's seed), so the samples
// of one object share one reference.
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "scene/Scene.h"
#include "trace/Tracer.h"

namespace ltm {

class ReferenceCache {
public:
    // What the reference depends on: the defect-free scene, the reference's seed and the
    // representation it is rendered in.
    static std::string key(const Scene& scene, std::uint64_t seed, Representation representation);

    // The reference stored for `key` (MeanX, MeanY, 2 per camera pixel), if any.
    std::optional<std::vector<float>> find(const std::string& key) const;
    // Records the reference for `key`.
    void store(const std::string& key, const std::vector<float>& reference);

    long reused() const;  // references find() returned, over the cache's life

private:
    mutable std::mutex mu_;
    std::map<std::string, std::vector<float>> entries_;
    mutable long reused_ = 0;
};

}  // namespace ltm
