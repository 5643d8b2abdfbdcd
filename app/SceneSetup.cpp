#include "app/SceneSetup.h"

#include <filesystem>
#include <fmt/format.h>
#include <iostream>

#include "app/Commands.h"
#include "scene/SceneLoader.h"
#include "scene/SceneSolid.h"
#include "study/SceneRun.h"

namespace ltm::app {

std::optional<LoadedScene> load_scene_and_solid(const std::string& path, StageReport& report, int& status,
                                                bool surfaces_only) {
    LoadedScene out;
    try {
        StageTimer t(&report, "parse");
        out.scene = load_scene(path);
        t.done(fmt::format("{} defect(s)", out.scene.defects.size()));
    } catch (const SceneError& e) {
        std::cerr << e.what() << "\n";
        status = 2;
        return std::nullopt;
    }
    print_scene_warnings(out.scene);
    try {
        out.solid = build_solid(out.scene, &report, surfaces_only);
    } catch (const SceneError& e) {
        std::cerr << e.what() << "\n";
        status = 2;
        return std::nullopt;
    } catch (const std::invalid_argument& e) {
        std::cerr << fmt::format("{}: {}\n", out.scene.source, e.what());
        status = 2;
        return std::nullopt;
    } catch (const TetGenError& e) {
        std::cerr << fmt::format("{}: {}\n", out.scene.source, e.what());
        status = 2;
        return std::nullopt;
    }
    return out;
}

void print_scene_warnings(const Scene& scene) {
    for (const std::string& w : scene.warnings) std::cerr << w << "\n";
}

std::string verbose_stages(const StageReport& report) {
    std::string out = report.to_text();
    if (!report.ran("boolean")) out += "  (no Boolean ran)\n";
    if (!report.ran("tetgen")) out += "  (no TetGen ran)\n";
    return out;
}

bool output_folder_ok(const std::string& command, const std::string& dir) {
    const std::filesystem::path p(dir);
    const auto parent = p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
    if (!std::filesystem::is_directory(parent)) {
        std::cerr << fmt::format("ltmsim {}: cannot write {}: folder {} does not exist\n", command, dir, parent.string());
        return false;
    }
    if (std::filesystem::exists(p) && !std::filesystem::is_directory(p)) {
        std::cerr << fmt::format("ltmsim {}: {} exists and is not a folder\n", command, dir);
        return false;
    }
    return true;
}

std::optional<Representation> resolve_representation(const std::string& command, const std::string& name,
                                                     const LoadedScene& loaded) {
    if (name == "auto") return auto_representation(loaded.solid);
    if (name == "refined") return Representation::Refined;
    if (name == "mesh-only") return Representation::MeshOnly;
    if (name != "analytic") throw std::invalid_argument("unknown representation '" + name + "'");
    std::string why;
    if (!Tracer::analytic_supported(loaded.solid, &why)) {
        std::cerr << fmt::format("ltmsim {}: {}: the analytic representation {}; use --representation refined\n", command,
                                 loaded.scene.source, why);
        return std::nullopt;
    }
    return Representation::Analytic;
}

void add_representation_option(CLI::App* cmd, std::string& value, const std::vector<std::string>& choices) {
    std::string help;
    for (const std::string& c : choices) {
        help += (help.empty() ? "" : " | ") + c;
        if (c == "auto") help += " (analytic when no defect cuts the glass, else refined)";
    }
    cmd->add_option("--representation", value, help)->check(CLI::IsMember(choices));
}

void add_estimator_options(CLI::App* cmd, EstimatorArgs& args) {
    cmd->add_option("--estimator", args.estimator,
                    "sample (one path per camera sample, Fresnel branch chosen at random) | split (both Fresnel "
                    "branches followed, weights R and T, for the first --split-depth interactions); overrides the "
                    "scene's tracing.estimator")
        ->check(CLI::IsMember({"sample", "split"}));
    cmd->add_option("--split-depth", args.split_depth,
                    fmt::format("Fresnel interactions split per path, 0 to {} (default: the scene's tracing.split_depth, "
                                "else {}); with --estimator split only",
                                kMaxSplitDepth, kDefaultSplitDepth))
        ->check(whole_number(0, kMaxSplitDepth));
}

bool apply_estimator_options(const std::string& command, const EstimatorArgs& args, Scene& scene) {
    if (!args.estimator.empty()) scene.tracing.estimator = args.estimator == "split" ? Estimator::Split : Estimator::Sample;
    if (args.split_depth < 0) return true;
    if (scene.tracing.estimator != Estimator::Split) {
        std::cerr << fmt::format("ltmsim {}: {}: --split-depth applies only to the split estimator (the estimator is "
                                 "sample{}); add --estimator split\n",
                                 command, scene.source, args.estimator.empty() ? ", the scene's" : "");
        return false;
    }
    scene.tracing.split_depth = args.split_depth;
    return true;
}

}  // namespace ltm::app
