#pragma once
// What every computing command does first: load the scene (strictly) and build its solid, turning
// bad input into one message and exit status 2.
#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "defects/SolidBuilder.h"
#include "geometry/StageReport.h"
#include "scene/Scene.h"
#include "trace/Tracer.h"

namespace ltm::app {

struct LoadedScene {
    Scene scene;
    Solid solid;
};

// On bad input prints the message to stderr, sets `status` to 2 and returns nothing; the solid is
// built only for a scene that loads, after its warnings are printed (print_scene_warnings).
// `surfaces_only`: no mesh unless a defect cuts the glass (for the analytic representation).
std::optional<LoadedScene> load_scene_and_solid(const std::string& path, StageReport& report, int& status,
                                                bool surfaces_only = false);

// The scene's warnings (Scene::warnings: a view of the object that is likely a unit slip), one line
// each on stderr.
void print_scene_warnings(const Scene& scene);

// The one parser of --representation, for every command that takes it:
//   auto       analytic when the tracer supports the solid analytically (no defect cuts the
//              glass), else refined (study/SceneRun.h, auto_representation);
//   refined | analytic | mesh-only   that representation; analytic is refused for a solid it
//              does not support, with the reason.
// `choices` restricts the names a command accepts (CLI11 checks them first, see
// add_representation_option). On a refusal prints "ltmsim COMMAND: SOURCE: the analytic
// representation ...; use --representation refined" and returns nothing (exit status 2).
std::optional<Representation> resolve_representation(const std::string& command, const std::string& name,
                                                     const LoadedScene& loaded);
// Whether `name` needs no mesh where closed forms exist (auto and analytic).
inline bool representation_uses_surfaces_only(const std::string& name) { return name == "auto" || name == "analytic"; }
// Adds --representation to `cmd`, accepting the given names (a subset of auto, refined, analytic, mesh-only).
void add_representation_option(CLI::App* cmd, std::string& value, const std::vector<std::string>& choices);

// --estimator sample|split and --split-depth N (0..kMaxSplitDepth): the scene's `tracing` section
// from the command line, which overrides it. Unset options (empty name, depth -1) keep the scene's.
struct EstimatorArgs {
    std::string estimator;
    int split_depth = -1;
};
void add_estimator_options(CLI::App* cmd, EstimatorArgs& args);
// Applies `args` to scene.tracing. --split-depth with an estimator that resolves to sample would be
// ignored, so it is refused: prints "ltmsim COMMAND: SOURCE: --split-depth applies only to ..." and
// returns false (exit status 2).
bool apply_estimator_options(const std::string& command, const EstimatorArgs& args, Scene& scene);

// The stages that ran (--verbose), then what did not run: "(no Boolean ran)" for a scene whose
// defects cut nothing, "(no TetGen ran)" for one without a meshed index region.
std::string verbose_stages(const StageReport& report);

// True if `dir`'s parent folder exists (the folder itself may be created); else prints why.
bool output_folder_ok(const std::string& command, const std::string& dir);

}  // namespace ltm::app
