#pragma once
// The resolved scene (every default filled in) as JSON, for run.json: what was actually run.
// Numbers are written exactly (io/Json.h: shortest round-trip form; inf as the string "inf").
#include <nlohmann/json_fwd.hpp>

#include "scene/Scene.h"

namespace ltm {

nlohmann::ordered_json scene_to_json(const Scene& scene);  // an io::Json (io/Json.h)
// The estimator ({"estimator": "split", "split_depth": 4} or {"estimator": "sample"}): the scene's
// "tracing" entry, and run.json's record of what the render used.
nlohmann::ordered_json tracing_to_json(const TracingDesc& tracing);

}  // namespace ltm
