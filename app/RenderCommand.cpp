// `ltmsim render SCENE -o DIR`: the light transport matrix DIR/ltm.npz and DIR/run.json; with
// --pattern IMAGE, the camera image for that display pattern (DIR/image.exr, DIR/image.png).
#include <filesystem>
#include <fmt/format.h>
#include <iostream>

#include "app/Commands.h"
#include "app/FeatureOutputs.h"
#include "app/SceneSetup.h"
#include "io/Image.h"
#include "scene/SceneJson.h"
#include "io/LtmFile.h"
#include "study/SceneRun.h"
#include "trace/Render.h"

namespace ltm::app {

namespace fs = std::filesystem;

namespace {

struct RenderArgs {
    std::string scene, dir, pattern, representation = "auto";
    int threads = 0;
    bool overwrite = false, verbose = false, no_robust = false;
    FeatureOptions features{0.0, 0.99, -1};  // dark block -1: automatic (write_features)
    EstimatorArgs estimator;                  // overrides the scene's tracing section
};

int run(const RenderArgs& a) {
    if (!output_folder_ok("render", a.dir)) return 2;
    std::vector<std::string> outputs = a.pattern.empty()
                                           ? std::vector<std::string>{"ltm.npz", "run.json", "features.exr", "features.npz"}
                                           : std::vector<std::string>{"image.exr", "image.npz", "image.png", "run.json"};
    if (!a.overwrite)
        for (const auto& f : outputs)
            if (fs::exists(fs::path(a.dir) / f)) {
                std::cerr << fmt::format("ltmsim render: {} exists; pass --overwrite to replace it\n",
                                         (fs::path(a.dir) / f).string());
                return 2;
            }
    StageReport report;
    int status = 0;
    // auto and analytic trace closed forms where no defect cuts the glass: no mesh is built then.
    auto loaded = load_scene_and_solid(a.scene, report, status, representation_uses_surfaces_only(a.representation));
    if (!loaded) return status;
    if (!apply_estimator_options("render", a.estimator, loaded->scene)) return 2;
    const Scene& scene = loaded->scene;  // with the estimator the render uses (run.json records it)

    if (a.features.dark_block > std::min(scene.display.resolution[0], scene.display.resolution[1])) {
        std::cerr << fmt::format("ltmsim render: --dark-block {} exceeds the display's {} x {} pixels ({})\n",
                                 a.features.dark_block, scene.display.resolution[0], scene.display.resolution[1], scene.source);
        return 2;
    }
    std::vector<float> pattern;
    if (!a.pattern.empty()) {
        try {
            const Image img = read_image(a.pattern);
            if (img.width != scene.display.resolution[0] || img.height != scene.display.resolution[1]) {
                std::cerr << fmt::format("ltmsim render: {}: the pattern is {} x {} pixels but the display is {} x {} "
                                         "(display.resolution in {})\n",
                                         a.pattern, img.width, img.height, scene.display.resolution[0],
                                         scene.display.resolution[1], scene.source);
                return 2;
            }
            pattern = pattern_values(img);
        } catch (const std::exception& e) {
            std::cerr << "ltmsim render: " << e.what() << "\n";
            return 2;
        }
    }

    const std::optional<Representation> chosen = resolve_representation("render", a.representation, *loaded);
    if (!chosen) return 2;
    const Representation representation = *chosen;

    SceneRun run;
    if (pattern.empty()) {
        // The matrix, its features and, for a scene with defects, the defect-free reference
        // (study/SceneRun.h): pixels whose paths met no defect are their own reference.
        SceneRunOptions so;
        so.representation = representation;
        so.robust = !a.no_robust;
        so.threads = a.threads;
        so.progress = true;
        so.features = a.features;
        run = run_scene(scene, loaded->solid, so, &report);
    } else {
        TracerOptions topt;
        topt.robust = !a.no_robust;
        topt.representation = representation;
        StageTimer t_setup(&report, "trace-setup");
        const Tracer tracer(scene, loaded->solid, topt);
        t_setup.done(to_string(topt.representation));
        RenderOptions ropt;
        ropt.threads = a.threads;
        ropt.progress = true;
        ropt.pattern = &pattern;
        StageTimer t_render(&report, "render");
        run.render = render(tracer, ropt);
        run.representation = representation;
        t_render.done(fmt::format("{} paths, {} segments, {:.3g} Mpaths/s", run.render.stats.paths,
                                  run.render.stats.segments, run.render.stats.paths / std::max(run.render.seconds, 1e-9) / 1e6));
    }
    const RenderResult& r = run.render;

    try {
        if (pattern.empty()) {
            write_render_folder(a.dir, scene, run, a.threads, report);
        } else {
            std::error_code ec;
            fs::create_directories(a.dir, ec);
            const fs::path dir(a.dir);
            const int N = scene.camera.resolution[0], M = scene.camera.resolution[1];
            std::vector<float> y(r.image.begin(), r.image.end()), se(r.image_stderr.begin(), r.image_stderr.end());
            std::vector<fs::path> written;
            try {
                write_exr((dir / "image.exr").string(), N, M, {{"Image", y}, {"StdError", se}});
                written.push_back(dir / "image.exr");
                write_npz_channels((dir / "image.npz").string(), N, M, {{"Image", y}, {"StdError", se}});
                written.push_back(dir / "image.npz");
                Image preview;
                preview.width = N;
                preview.height = M;
                preview.channels = 1;
                double peak = 0;
                for (double v : r.image) peak = std::max(peak, v);
                for (double v : r.image) preview.data.push_back(static_cast<float>(peak > 0 ? v / peak : 0.0));
                write_png((dir / "image.png").string(), preview);
                written.push_back(dir / "image.png");
                write_run_json(a.dir, scene, r, representation, a.threads,
                               {{"pattern", a.pattern}, {"image", "image.exr"}},
                               report);
            } catch (...) {
                for (const auto& p : written) fs::remove(p, ec);
                throw;
            }
        }
    } catch (const std::exception& e) {
        std::cerr << "ltmsim render: " << e.what() << "\n";
        return 1;
    }
    if (a.verbose) std::cerr << fmt::format("ltmsim render {} -> {}\n", a.scene, a.dir) << verbose_stages(report);
    if (r.stats.nan_events > 0) std::cerr << fmt::format("warning: {} paths produced a NaN (see run.json)\n", r.stats.nan_events);
    return 0;
}

}  // namespace

void add_render_command(CLI::App& app) {
    auto args = std::make_shared<RenderArgs>();
    CLI::App* cmd = app.add_subcommand("render", "Render the light transport matrix (or a pattern's camera image)");
    cmd->add_option("scene", args->scene, "Scene file (YAML)")->required();
    cmd->add_option("-o,--output", args->dir, "Output folder (created if missing; its parent must exist)")->required();
    cmd->add_option("--pattern", args->pattern, "Render y = T x for this display pattern image (PNG or EXR) instead");
    cmd->add_option("--threads", args->threads, "Threads (default: all cores); results do not depend on it")
        ->check(CLI::NonNegativeNumber);
    add_representation_option(cmd, args->representation, {"auto", "refined", "analytic", "mesh-only"});
    cmd->add_flag("--no-robust", args->no_robust, "Embree's fast (non-watertight) traversal");
    add_estimator_options(cmd, args->estimator);
    cmd->add_option("--dark-block", args->features.dark_block, "DarkField: side of the centred block switched off, display pixels (default: 60, or the display's smaller side if less)");
    cmd->add_flag("--overwrite", args->overwrite, "Replace existing outputs in the folder");
    cmd->add_flag("-v,--verbose", args->verbose, "Print the stages that ran, with times and sizes");
    cmd->callback([args] { run_guarded("render", [&] { return run(*args); }); });
}

}  // namespace ltm::app
