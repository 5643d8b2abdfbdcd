#pragma once
// One bad-input problem in a file ltmsim reads (a scene file, a dataset spec, a rays file), located
// as an editor shows it. Readers of such files (scene/StrictYaml.h, io/Json.h) stop at the first
// problem and throw one; the commands turn it into exit status 2.
#include <stdexcept>
#include <string>

namespace ltm {

// what() is the complete one-paragraph message:
//   "<file>:<line>:<column>: <key path>: <message>"
//   "<file>:<line>:<column>: <message>"               (no key path, e.g. malformed YAML)
//   "<file>:<line>: <message>"                         (column = 0: a whole line is at fault, e.g. a
//                                                       JSON-lines record with a wrong key)
//   "<file>: <message>"                                (line = 0, e.g. "cannot read scene file: <reason>")
// The key path names the value from the document root, e.g. "defects[2].radius",
// "camera.resolution[0]", "object.r1".
struct InputError : std::runtime_error {
    InputError(std::string file, int line, int column, std::string key_path, std::string message);

    std::string file;
    int line = 0;     // 1-based; 0 when the file could not be read
    int column = 0;   // 1-based; 0 when the file could not be read or the whole line is meant
    std::string key_path;
    std::string message;  // the bare message, without location and key path
};

}  // namespace ltm
