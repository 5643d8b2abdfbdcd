#pragma once
// The resolved scene (every default filled in) as JSON, for run.json: what was actually run.
#include <string>

#include "scene/Scene.h"

namespace ltm {

std::string scene_to_json(const Scene& scene, int indent = 2);
// A double as JSON: shortest round-trip form; inf as the string "inf" (JSON has no infinity).
std::string json_number(double v);
// A string as a JSON string literal (quoted, escaped).
std::string json_string(const std::string& s);

}  // namespace ltm
