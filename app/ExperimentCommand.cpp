// `ltmsim experiment FOLDER -o OUT`: renders every scene an experiment file lists, computes their
// features, measures them as an instrument would (acquire/Instrument.h: each feature with the
// pattern family and count it needs, through the sensor model), and puts numbers on both
// (study/Experiment.h): the contrast-to-noise ratio of every defect in every image, the false
// positives of the defect-free scene, the best new feature (judged on the measured images).
// Writes OUT/<scene>/ (as `render`, plus regions.json: the defect and surround pixels measured),
// OUT/contrast.csv, OUT/false_positives.csv, OUT/contrast.md and OUT/montage.png (rows: images,
// columns: scenes), as the paper's Fig. 3. docs/experiment.md has the file format and the outputs.
#include <filesystem>
#include <fmt/format.h>
#include <iostream>

#include "app/Commands.h"
#include "app/FeatureOutputs.h"
#include "acquire/Instrument.h"
#include "app/SceneSetup.h"
#include "app/SensorFile.h"
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
    std::string folder, out, sensor;
    int threads = 0;
    bool overwrite = false;
};

int run(const ExperimentArgs& a) {
    ExperimentSpec spec;
    std::vector<ExperimentScene> scenes;
    // Every scene is loaded (and its solid built) first, so a bad one stops the run before
    // anything is rendered.
    acquire::SensorModel sensor;
    try {
        if (!a.sensor.empty()) sensor = load_sensor_file(a.sensor);
        const std::string bad = acquire::check(sensor);
        if (!bad.empty()) throw std::invalid_argument(a.sensor + ": " + bad);
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
    // The scenes share one defect-free reference of the deflection map (study/ReferenceCache.h).
    ReferenceCache references;
    for (ExperimentScene& s : scenes) {
        std::cerr << fmt::format("rendering {} ({})\n", s.file, s.label);
        render_experiment_scene(s, a.threads, &references);
        StageReport report;
        write_render_folder((fs::path(a.out) / s.stem).string(), s.scene, s.run, a.threads, report);
    }
    // Every scene's features as the instrument measures them (the deflection map against the
    // same rendered reference as the rendered images').
    Measurement measured;
    const acquire::CameraModel& c = sensor.camera;
    measured.instrument = fmt::format(
        "{}camera: full well {:g} e-, exposure {:g}, read noise {:g} e-, dark level {:g} e-, {} bits; display: "
        "black level {:g}, gamma {:g}, {} bits; sensor seed {}",
        a.sensor.empty() ? "acquire's default sensor, " : a.sensor + ", ", c.full_well, c.exposure, c.read_noise,
        c.dark_level, c.bits, sensor.display.black_level, sensor.display.gamma, sensor.display.bits, sensor.seed);
    for (ExperimentScene& s : scenes) {
        std::cerr << fmt::format("measuring {} as an instrument would\n", s.file);
        const acquire::InstrumentImages m =
            acquire::measure_features(s.run.render.T, s.scene.camera.resolution[0], s.scene.camera.resolution[1],
                                      display_grid(s.scene), sensor, a.threads);
        MeasuredImages mi{m.features, m.how, m.resolution};
        add_deflection(mi.features, s.run.reference);
        for (const char* ch : {"DeflectionX", "DeflectionY", "Deflection"}) {
            mi.how[ch] = m.how.at("MeanX");
            mi.resolution[ch] = m.resolution.at("MeanX");
        }
        measured.scenes.push_back(std::move(mi));
    }
    const ExperimentResult r = evaluate_experiment(spec, scenes, &measured);
    // The regions each scene's numbers were measured in, for later measurements of the same scene
    // (ltmsim acquire judges its CNR in exactly these pixels).
    for (std::size_t i = 0; i < scenes.size(); ++i)
        io::write_json_file((fs::path(a.out) / scenes[i].stem / "regions.json").string(), regions_json(r.regions[i]),
                            "regions file", -1);
    io::write_file((fs::path(a.out) / "contrast.csv").string(), r.csv, "contrast table");
    io::write_file((fs::path(a.out) / "false_positives.csv").string(), r.false_positives_csv, "false-positive table");
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
    cmd->add_option("--sensor", args->sensor,
                    "A YAML file with a sensor section for the measured images (default: acquire's documented camera and LCD)");
    add_threads_option(cmd, args->threads, "Threads (default: all cores)");
    cmd->add_flag("--overwrite", args->overwrite, "Replace earlier results in the output folder");
    cmd->callback([args] { run_guarded("experiment", args->threads, [&] { return run(*args); }); });
}

}  // namespace ltm::app
