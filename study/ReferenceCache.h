#pragma once
// The defect-free reference of the deflection map, computed once per object and shared by every
// scene that has the same object under the same camera, display and random numbers (the scenes
// of an experiment): study/SceneRun.h renders a pixel's reference only if no scene before it did.
//
// Why this never changes a result. A pixel's reference is the mean display position of its row of
// the defect-free object's T. That row depends on the defect-free scene (object, camera, display,
// mesh options), the render's seed, and the tracer's representation only: a render of a subset of
// pixels gives each pixel exactly the values a full render gives it (RenderOptions::pixels), so a
// value computed for one scene is the value any other scene with the same key would compute. The
// key holds all of these (the scene as JSON without its defects and without the file it came
// from); scenes whose key differs share nothing. Dataset samples draw their own random numbers
// (RenderOptions::stream), so their keys differ and each renders its own reference.
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "scene/Scene.h"
#include "trace/Tracer.h"

namespace ltm {

class ReferenceCache {
public:
    // What a pixel's reference depends on: the defect-free scene, the seed and the representation.
    static std::string key(const Scene& scene, std::uint64_t seed, Representation representation);

    // The pixels of `pixels` (ascending) whose reference is known for `key`: their MeanX, MeanY go
    // into ref (2 per camera pixel, camera_pixels of them); the others are returned.
    std::vector<long> fill(const std::string& key, const std::vector<long>& pixels, long camera_pixels,
                           std::vector<float>& ref) const;
    // Records the reference of `pixels` (their values in ref, laid out as for fill).
    void store(const std::string& key, const std::vector<long>& pixels, long camera_pixels, const std::vector<float>& ref);

    long reused() const;  // pixels fill() found, over the cache's life

private:
    struct Entry {
        std::vector<float> mean;  // 2 per camera pixel
        std::vector<char> known;
    };
    mutable std::mutex mu_;
    std::map<std::string, Entry> entries_;
    mutable long reused_ = 0;
};

}  // namespace ltm
