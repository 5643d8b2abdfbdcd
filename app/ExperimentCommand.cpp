// `ltmsim experiment FOLDER -o OUT`: renders every scene an experiment file lists, computes their
// features, and puts numbers on them (study/Experiment.h): the contrast-to-noise ratio of every
// defect in every image, the false positives of the defect-free scene, the best new feature.
// Writes OUT/<scene>/ (as `render`, plus regions.json: the defect and surround pixels measured), OUT/contrast.csv, OUT/contrast.md and OUT/montage.png (rows:
// images, columns: scenes), as the paper's Fig. 3.
#include <filesystem>
#include <fmt/format.h>
#include <iostream>

#include "app/Commands.h"
#include "app/FeatureOutputs.h"
#include "app/SceneSetup.h"
#include "io/Image.h"
#include "io/AtomicFile.h"
#include "io/Json.h"
#include "io/InputError.h"
#include "study/Experiment.h"
#include "geometry/TetMesh.h"

namespace ltm::app {

namespace fs = std::filesystem;

namespace {

struct ExperimentArgs {
    std::string folder, out;
    int threads = 0;
    bool overwrite = false;
};

int run(const ExperimentArgs& a) {
    ExperimentSpec spec;
    std::vector<ExperimentScene> scenes;
    // Every scene is loaded (and its solid built) first, so a bad one stops the run before
    // anything is rendered.
    try {
        spec = load_experiment((fs::path(a.folder) / "experiment.yaml").string());
        scenes = load_experiment_scenes(spec);
    } catch (const InputError& e) {
        std::cerr << e.what() << "\n";
        return 2;
    } catch (const std::invalid_argument& e) {
        std::cerr << e.what() << "\n";
        return 2;
    } catch (const TetGenError& e) {
        std::cerr << e.what() << "\n";
        return 2;
    }
    for (const ExperimentScene& s : scenes) print_scene_warnings(s.scene);
    if (!output_folder_ok("experiment", a.out)) return 2;
    if (!a.overwrite && fs::exists(fs::path(a.out) / "contrast.csv")) {
        std::cerr << fmt::format("ltmsim experiment: {} holds results; pass --overwrite to replace them\n", a.out);
        return 2;
    }
    fs::create_directories(a.out);
    // The reference scene first: a defect-free scene gives every pixel's reference, which the
    // others then reuse instead of rendering their own.
    // (The order of rendering only; the montage keeps the spec's order.)
    std::vector<ExperimentScene*> order;
    for (ExperimentScene& s : scenes)
        if (s.scene.defects.empty()) order.push_back(&s);
    for (ExperimentScene& s : scenes)
        if (!s.scene.defects.empty()) order.push_back(&s);
    ReferenceCache references;
    for (ExperimentScene* p : order) {
        ExperimentScene& s = *p;
        std::cerr << fmt::format("rendering {} ({})\n", s.file, s.label);
        render_experiment_scene(s, a.threads, &references);
        StageReport report;
        write_render_folder((fs::path(a.out) / s.stem).string(), s.scene, s.run, a.threads, report);
    }
    const ExperimentResult r = evaluate_experiment(spec, scenes);
    // The regions each scene's numbers were measured in, for later measurements of the same scene
    // (ltmsim acquire judges its CNR in exactly these pixels).
    for (std::size_t i = 0; i < scenes.size(); ++i)
        io::write_json_file((fs::path(a.out) / scenes[i].stem / "regions.json").string(), regions_json(r.regions[i]),
                            "regions file", -1);
    io::write_file((fs::path(a.out) / "contrast.csv").string(), r.csv, "contrast table");
    io::write_file((fs::path(a.out) / "contrast.md").string(), r.markdown, "contrast table");
    write_png((fs::path(a.out) / "montage.png").string(), r.montage);
    std::cout << r.markdown;
    return 0;
}

}  // namespace

void add_experiment_command(CLI::App& app) {
    auto args = std::make_shared<ExperimentArgs>();
    CLI::App* cmd = app.add_subcommand("experiment", "Render an experiment's scenes; contrast tables and a montage");
    cmd->add_option("folder", args->folder, "A folder with experiment.yaml and its scenes")->required();
    cmd->add_option("-o,--output", args->out, "Output folder")->required();
    add_threads_option(cmd, args->threads, "Threads (default: all cores)");
    cmd->add_flag("--overwrite", args->overwrite, "Replace earlier results in the output folder");
    cmd->callback([args] { run_guarded("experiment", args->threads, [&] { return run(*args); }); });
}

}  // namespace ltm::app
