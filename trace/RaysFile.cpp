#include "trace/RaysFile.h"

#include <fmt/format.h>

#include "io/Json.h"

namespace ltm {

namespace {

std::vector<InputRay> read_lines(io::JsonLinesReader& lines) {
    std::vector<InputRay> out;
    for (io::Json v; lines.next(v);) {
        if (!v.is_object()) lines.fail("expected an object {\"origin\": [x, y, z], \"direction\": [dx, dy, dz]}");
        InputRay r;
        for (const auto& [key, val] : v.items()) {
            if (key != "origin" && key != "direction")
                lines.fail(fmt::format("unknown key \"{}\" (expected \"origin\" and \"direction\")", key));
            if (!val.is_array() || val.size() != 3)
                lines.fail(fmt::format("\"{}\" must be a list of 3 numbers", key));
            Vec3 x;
            for (int i = 0; i < 3; ++i) {
                const io::Json& c = val[static_cast<size_t>(i)];
                if (!c.is_number()) lines.fail(fmt::format("\"{}\" must be a list of 3 numbers", key));
                x[i] = c.get<double>();
            }
            if (!is_finite(x)) lines.fail(fmt::format("\"{}\" must be finite", key));
            (key == "origin" ? r.origin : r.direction) = x;
        }
        if (!v.contains("origin")) lines.fail("missing key \"origin\"");
        if (!v.contains("direction")) lines.fail("missing key \"direction\"");
        // Any finite non-zero vector is a direction (the tracer normalises it, whatever its size).
        if (r.direction == Vec3{0, 0, 0}) lines.fail("\"direction\" must not be the zero vector");
        out.push_back(r);
    }
    return out;
}

}  // namespace

std::vector<InputRay> read_rays(const std::string& path) {
    io::JsonLinesReader lines(path, "rays file");
    return read_lines(lines);
}

std::vector<InputRay> read_rays(std::istream& in, const std::string& name) {
    io::JsonLinesReader lines(in, name);
    return read_lines(lines);
}

}  // namespace ltm
