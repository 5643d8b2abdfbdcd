#include "study/ReferenceCache.h"

#include "io/Json.h"
#include "scene/SceneJson.h"
#include "scene/SceneSolid.h"

namespace ltm {

std::string ReferenceCache::key(const Scene& scene, std::uint64_t seed, Representation representation) {
    auto j = scene_to_json(defect_free(scene));
    j.erase("source");  // the file a scene came from does not change its paths
    j.erase("seed");    // the reference's own seed follows
    j.erase("reference_seed");
    return j.dump() + "|seed " + std::to_string(seed) + "|" + to_string(representation);
}

std::optional<std::vector<float>> ReferenceCache::find(const std::string& key) const {
    std::lock_guard<std::mutex> lock(mu_);
    const auto it = entries_.find(key);
    if (it == entries_.end()) return std::nullopt;
    ++reused_;
    return it->second;
}

void ReferenceCache::store(const std::string& key, const std::vector<float>& reference) {
    std::lock_guard<std::mutex> lock(mu_);
    entries_[key] = reference;
}

long ReferenceCache::reused() const {
    std::lock_guard<std::mutex> lock(mu_);
    return reused_;
}

}  // namespace ltm
