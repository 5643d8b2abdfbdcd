#include "geometry/StageReport.h"

#include <fmt/format.h>

namespace ltm {

std::string StageReport::to_text() const {
    std::string out;
    for (const auto& s : stages_) out += fmt::format("  {:<12} {:9.3f} ms  {}\n", s.name, 1e3 * s.seconds, s.detail);
    return out;
}

static std::string json_escape(const std::string& s) {
    std::string o;
    for (char c : s) {
        if (c == '"' || c == '\\') { o += '\\'; o += c; }
        else if (static_cast<unsigned char>(c) < 0x20) o += fmt::format("\\u{:04x}", static_cast<int>(c));
        else o += c;
    }
    return o;
}

std::string StageReport::to_json() const {
    std::string out = "[";
    for (size_t i = 0; i < stages_.size(); ++i) {
        const auto& s = stages_[i];
        out += fmt::format("{}{{\"stage\": \"{}\", \"seconds\": {:.6g}, \"detail\": \"{}\"}}", i ? ", " : "",
                           json_escape(s.name), s.seconds, json_escape(s.detail));
    }
    return out + "]";
}

}  // namespace ltm
