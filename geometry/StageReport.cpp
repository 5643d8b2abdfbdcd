#include "geometry/StageReport.h"

#include <fmt/format.h>

#include "io/Json.h"

namespace ltm {

std::string StageReport::to_text() const {
    std::string out;
    for (const auto& s : stages_) out += fmt::format("  {:<12} {:9.3f} ms  {}\n", s.name, 1e3 * s.seconds, s.detail);
    return out;
}

io::Json StageReport::to_json() const {
    io::Json out = io::Json::array();
    for (const auto& s : stages_) out.push_back({{"stage", s.name}, {"seconds", s.seconds}, {"detail", s.detail}});
    return out;
}

}  // namespace ltm
