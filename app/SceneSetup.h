#pragma once
// What every computing command does first: load the scene (strictly) and build its solid, turning
// bad input into one message and exit status 2.
#include <optional>
#include <string>

#include "defects/SolidBuilder.h"
#include "geometry/StageReport.h"
#include "scene/Scene.h"

namespace ltm::app {

struct LoadedScene {
    Scene scene;
    Solid solid;
};

// On bad input prints the message to stderr, sets `status` to 2 and returns nothing.
// `surfaces_only`: no mesh unless a defect cuts the glass (for the analytic representation).
std::optional<LoadedScene> load_scene_and_solid(const std::string& path, StageReport& report, int& status,
                                                bool surfaces_only = false);

// The stages that ran (--verbose), then what did not run: "(no Boolean ran)" for a scene whose
// defects cut nothing, "(no TetGen ran)" for one without a meshed index region.
std::string verbose_stages(const StageReport& report);

// True if `dir`'s parent folder exists (the folder itself may be created); else prints why.
bool output_folder_ok(const std::string& command, const std::string& dir);

}  // namespace ltm::app
