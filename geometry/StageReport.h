#pragma once
// What ran, how long it took and how big its output was: printed by --verbose, written to the
// stats file, and checked by tests (a defect-free scene must not run a Boolean).
#include <chrono>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

namespace ltm {

struct Stage {
    std::string name;      // e.g. "parse", "tessellate", "boolean"
    double seconds = 0;
    std::string detail;    // sizes, counts
};

class StageReport {
public:
    void add(std::string name, double seconds, std::string detail) {
        stages_.push_back({std::move(name), seconds, std::move(detail)});
    }
    const std::vector<Stage>& stages() const { return stages_; }
    bool ran(const std::string& name) const {
        for (const auto& s : stages_)
            if (s.name == name) return true;
        return false;
    }
    std::string to_text() const;
    // [{"stage": name, "seconds": s, "detail": text}, ...] in the order run (an io::Json).
    nlohmann::ordered_json to_json() const;

private:
    std::vector<Stage> stages_;
};

// Times a scope; call done() with the detail to record it.
class StageTimer {
public:
    StageTimer(StageReport* report, std::string name)
        : report_(report), name_(std::move(name)), t0_(std::chrono::steady_clock::now()) {}
    double elapsed() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    }
    void done(std::string detail) {
        if (report_) report_->add(name_, elapsed(), std::move(detail));
        report_ = nullptr;
    }

private:
    StageReport* report_;
    std::string name_;
    std::chrono::steady_clock::time_point t0_;
};

}  // namespace ltm
