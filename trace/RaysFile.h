#pragma once
// The rays file of `ltmsim trace-rays` (docs/conventions.md, "Command line"): JSON lines, one ray
// per line, {"origin": [x, y, z], "direction": [dx, dy, dz]} in mm, in the scene's frame. Blank
// lines are allowed (and counted). Every line is checked before anything is traced:
//   - strict JSON (io/Json.h): a malformed line, a duplicate key or a number beyond a double is
//     "FILE:LINE:COLUMN: malformed JSON: ...";
//   - an object with exactly the keys origin and direction, each a list of 3 finite numbers, the
//     direction not the zero vector (any other length is normalised by the tracer): otherwise
//     "FILE:LINE: ...";
//   - a line longer than io::kMaxJsonLine bytes is refused after reading that much of it.
// Errors are InputError (io/InputError.h); the command turns them into exit status 2.
#include <istream>
#include <string>
#include <vector>

#include "geometry/Vec3.h"

namespace ltm {

struct InputRay {
    Vec3 origin, direction;
};

std::vector<InputRay> read_rays(const std::string& path);
// The same from a stream; `name` stands for the file in messages.
std::vector<InputRay> read_rays(std::istream& in, const std::string& name);

}  // namespace ltm
