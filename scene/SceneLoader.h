#pragma once
// The strict scene-file loader (docs/scene-format.md).
//
// A scene file is data: every key is known, every value has the expected type and range, and the
// geometry is physically possible, or loading fails with one SceneError. Nothing is silently
// repaired, defaulted over a bad value or ignored.
//
// Error locations (1-based line and column, as an editor shows them):
//   unknown or duplicate key            -> the key itself
//   wrong type or out-of-range value    -> the value (the list element, when one element is bad)
//   missing required key                -> the mapping that lacks it
//   impossible object or defect geometry-> the value of the key the problem names (the defect's
//                                          mapping when the key is not in the file)
//   malformed YAML                      -> where yaml-cpp stopped
// Checks run in file order (each mapping's entries in order, then its missing keys, then the
// geometry of the object / of each defect once it is complete), and the first problem wins.
#include <yaml-cpp/yaml.h>

#include <string>

#include "io/InputError.h"
#include "scene/Scene.h"

namespace ltm {

// A problem in a scene file: an InputError (io/InputError.h), e.g.
// "scene.yaml:9:47: defects[0].radius: must be a positive length (mm), got -0.1".
// The loader is built on the strict YAML engine of scene/StrictYaml.h.
using SceneError = InputError;

// Reads and parses the file at `path`; Scene::source is set to `path`.
// Throws SceneError on any bad input.
Scene load_scene(const std::string& path);

// Parses YAML text; `file_name_for_messages` is used in error messages and as Scene::source.
// Throws SceneError on any bad input.
Scene parse_scene(const std::string& yaml_text, const std::string& file_name_for_messages);

// Parses a scene given as a mapping inside another YAML document (the inline `scene:` of a
// dataset spec). Locations are those of that document, named `file` in messages and as
// Scene::source; key paths are the scene file's own, behind `prefix`, the mapping's key path in
// its document: prefix "scene" reports "scene.object.r1", "" reports "object.r1". Where a scene
// file reports at its document start (the default display.z, a missing object), this reports at
// the mapping. A caller that reads the mapping as an entry `scene: ...` should check it is a
// mapping first (yaml::Reader::require_map), so that an empty value is reported at its key.
// Throws SceneError on any bad input.
Scene parse_scene_node(const YAML::Node& root, const std::string& file, const std::string& prefix = "");

// A problem with the scene found after loading (building its solid), located as the loader
// locates its own: at the value of `key` (a key path from the scene's root, "defects[2].radius"),
// or of its nearest enclosing key the file gives ("defects[2]": the defect's mapping), with the
// key path behind the scene's prefix. A scene made in memory has no locations: then
// "<source>: <key path>: <message>".
InputError scene_error(const Scene& scene, const std::string& key, const std::string& message);

}  // namespace ltm
