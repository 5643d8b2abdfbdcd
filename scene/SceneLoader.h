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
#include <stdexcept>
#include <string>

#include "scene/Scene.h"

namespace ltm {

// One bad-input problem in a scene file. what() is the complete one-paragraph message:
//   "<file>:<line>:<column>: <key path>: <message>"
//   "<file>:<line>:<column>: <message>"               (no key path, e.g. malformed YAML)
//   "<file>: cannot read scene file: <reason>"         (unreadable file; line = column = 0)
// The key path names the value from the document root, e.g. "defects[2].radius",
// "camera.resolution[0]", "object.r1".
struct SceneError : std::runtime_error {
    SceneError(std::string file, int line, int column, std::string key_path, std::string message);

    std::string file;
    int line = 0;     // 1-based; 0 when the file could not be read
    int column = 0;   // 1-based; 0 when the file could not be read
    std::string key_path;
    std::string message;  // the bare message, without location and key path
};

// Reads and parses the file at `path`; Scene::source is set to `path`.
// Throws SceneError on any bad input.
Scene load_scene(const std::string& path);

// Parses YAML text; `file_name_for_messages` is used in error messages and as Scene::source.
// Throws SceneError on any bad input.
Scene parse_scene(const std::string& yaml_text, const std::string& file_name_for_messages);

}  // namespace ltm
