// `ltmsim render SCENE -o DIR`: the light transport matrix DIR/ltm.npz and DIR/run.json; with
// --pattern IMAGE, the camera image for that display pattern (DIR/image.exr, DIR/image.png).
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <limits>
#include <optional>

#include "app/Commands.h"
#include "app/FeatureOutputs.h"
#include "app/SceneSetup.h"
#include "io/AtomicFile.h"
#include "io/Image.h"
#include "scene/SceneJson.h"
#include "io/LtmFile.h"
#include "io/PeakRss.h"
#include "study/SceneRun.h"
#include "trace/Render.h"

namespace ltm::app {

namespace fs = std::filesystem;

namespace {

struct RenderArgs {
    std::string scene, dir, pattern, representation = "auto";
    int threads = 0;
    bool overwrite = false, verbose = false, no_robust = false, no_previews = false;
    FeatureOptions features{0.0, 0.99, -1};  // dark block -1: automatic (write_features)
    EstimatorArgs estimator;                  // overrides the scene's tracing section
    std::string max_memory;                   // GiB, as typed
    bool max_memory_given = false;            // else the default
};

// The default budget for T in memory: half the machine's physical memory, so that T, its feature
// images and the writing of the archive fit beside what else runs; 0 where the system does not
// say (then T is always kept whole).
std::size_t default_max_memory() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page <= 0) return 0;
    return static_cast<std::size_t>(pages) / 2 * static_cast<std::size_t>(page);
}

// --max-memory's value in bytes, or nullopt after printing why it is not a positive number of GiB.
std::optional<std::size_t> parse_max_memory(const std::string& text, bool given) {
    if (!given) return default_max_memory();
    double gib = 0;
    std::size_t used = 0;
    try {
        gib = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != text.size() || !std::isfinite(gib)) {
        std::cerr << fmt::format("ltmsim render: --max-memory: '{}' is not a number (the budget for T in memory, in GiB, "
                                 "e.g. --max-memory 8 or 0.5)\n",
                                 text);
        return std::nullopt;
    }
    if (gib <= 0) {
        std::cerr << fmt::format("ltmsim render: --max-memory: {} GiB is not positive (the budget for T in memory must be > 0; "
                                 "leave the option out for the default, half the physical memory)\n",
                                 text);
        return std::nullopt;
    }
    // At least one byte: a tiny budget streams every row (how the tests force streaming).
    const double bytes = std::ldexp(gib, 30);
    return bytes >= 1.8e19 ? std::numeric_limits<std::size_t>::max() : std::max<std::size_t>(1, static_cast<std::size_t>(bytes));
}

// The line a successful render prints on stdout: what it wrote where, and how fast it traced.
std::string render_summary(const RenderArgs& a, const Scene& scene, const SceneRun& run) {
    const RenderResult& r = run.render;
    const int N = scene.camera.resolution[0], M = scene.camera.resolution[1];
    std::string files;
    if (a.pattern.empty())
        files = fmt::format("ltm.npz (T {} x {}, {} nonzeros), features.exr and features.npz ({} images{}), reference.exr, "
                            "run.json",
                            static_cast<long>(N) * M, static_cast<long>(scene.display.resolution[0]) * scene.display.resolution[1],
                            r.nnz, run.features.channels.size(), a.no_previews ? "" : ", previews in features/");
    else
        files = fmt::format("image.exr and image.npz ({} x {} image of {}){}, run.json", N, M, a.pattern,
                            a.no_previews ? "" : ", image.png");
    return fmt::format("ltmsim render: wrote {}: {}; {} paths in {:.3g} s, {:.3g} Mpaths/s", (fs::path(a.dir) / "").string(),
                       files, r.stats.paths, r.seconds, r.stats.paths / std::max(r.seconds, 1e-9) / 1e6);
}

int run(const RenderArgs& a) {
    const std::optional<std::size_t> max_memory = parse_max_memory(a.max_memory, a.max_memory_given);
    if (!max_memory) return 2;
    if (!a.pattern.empty() && a.max_memory_given) {
        std::cerr << "ltmsim render: --max-memory applies to T; a --pattern render keeps no T (only its image)\n";
        return 2;
    }
    if (!output_folder_ok("render", a.dir)) return 2;
    std::vector<std::string> outputs;
    for (const char* f : a.pattern.empty() ? render_folder_files() : std::vector<const char*>{"image.exr", "image.npz", "image.png", "run.json"})
        outputs.push_back((fs::path(a.dir) / f).string());
    if (!outputs_may_be_written("render", outputs, a.overwrite)) return 2;
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
        // The matrix, its features and the defect-free reference of the deflection map, rendered
        // with random numbers of its own (study/SceneRun.h).
        SceneRunOptions so;
        so.representation = representation;
        so.robust = !a.no_robust;
        so.threads = a.threads;
        so.progress = true;
        so.features = a.features;
        so.max_matrix_bytes = *max_memory;
        so.stream_path = (fs::path(a.dir) / "ltm.npz").string();
        so.measure_memory = true;
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
        const io::PeakRssMeter meter;
        run.render = render(tracer, ropt);
        run.render_memory = {true, meter.peak_bytes(), meter.start_bytes(), meter.per_run(), meter.method()};
        run.representation = representation;
        t_render.done(fmt::format("{} paths, {} segments, {:.3g} Mpaths/s", run.render.stats.paths,
                                  run.render.stats.segments, run.render.stats.paths / std::max(run.render.seconds, 1e-9) / 1e6));
    }
    const RenderResult& r = run.render;

    try {
        if (pattern.empty()) {
            write_render_folder(a.dir, scene, run, a.threads, report,
                                memory_json(run.render_memory, r,
                                            static_cast<std::int64_t>(scene.camera.resolution[0]) * scene.camera.resolution[1],
                                            *max_memory),
                                !a.no_previews);
        } else {
            std::error_code ec;
            fs::create_directories(a.dir, ec);
            const fs::path dir(a.dir);
            const int N = scene.camera.resolution[0], M = scene.camera.resolution[1];
            std::vector<float> y(r.image.begin(), r.image.end()), se(r.image_stderr.begin(), r.image_stderr.end());
            std::vector<fs::path> written;
            try {
                // Made durable together, as a render folder's files are (write_render_folder): a
                // failure before the group's commit leaves every path as it was; after, the files
                // in place are removed (run.json, written last, marks a complete folder).
                io::CommitGroup group;
                write_exr((dir / "image.exr").string(), N, M, {{"Image", y}, {"StdError", se}}, &group);
                write_npz_channels((dir / "image.npz").string(), N, M, {{"Image", y}, {"StdError", se}}, &group);
                if (!a.no_previews) {
                    Image preview;
                    preview.width = N;
                    preview.height = M;
                    preview.channels = 1;
                    double peak = 0;
                    for (double v : r.image) peak = std::max(peak, v);
                    for (double v : r.image) preview.data.push_back(static_cast<float>(peak > 0 ? v / peak : 0.0));
                    write_png((dir / "image.png").string(), preview, &group);
                }
                written = {dir / "image.exr", dir / "image.npz"};
                if (!a.no_previews) written.push_back(dir / "image.png");
                group.commit();
                write_run_json(a.dir, scene, r, representation, a.threads,
                               {{"pattern", a.pattern}, {"image", "image.exr"}, {"previews", !a.no_previews}},
                               report, memory_json(run.render_memory, r, 0, 0));
            } catch (...) {
                for (const auto& p : written) fs::remove(p, ec);
                throw;
            }
        }
    } catch (const std::exception& e) {
        std::cerr << "ltmsim render: " << e.what() << "\n";
        return 1;
    }
    std::cout << render_summary(a, scene, run) << std::endl;
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
    add_threads_option(cmd, args->threads, "Threads (default: all cores); results do not depend on it");
    add_representation_option(cmd, args->representation, {"auto", "refined", "analytic", "mesh-only"});
    cmd->add_flag("--no-robust", args->no_robust, "Embree's fast (non-watertight) traversal");
    add_estimator_options(cmd, args->estimator);
    cmd->add_option("--dark-block", args->features.dark_block, "DarkField: side of the centred block switched off, display pixels (default: 60, or the display's smaller side if less)")
        ->check(whole_number(0, kMaxInt));
    CLI::Option* max_memory = cmd->add_option("--max-memory", args->max_memory,
                    "Budget for T in memory, GiB (default: half the physical memory); a larger T is traced in row blocks "
                    "and streamed to ltm.npz (features from the same blocks)");
    cmd->add_flag("--overwrite", args->overwrite, "Replace existing outputs in the folder");
    cmd->add_flag("--no-previews", args->no_previews,
                  "Leave out the PNG previews DIR/features/*.png (the features are in features.exr and .npz)");
    cmd->add_flag("-v,--verbose", args->verbose, "Print the stages that ran, with times and sizes");
    cmd->callback([args, max_memory] {
        args->max_memory_given = max_memory->count() > 0;
        run_guarded("render", args->threads, [&] { return run(*args); });
    });
}

}  // namespace ltm::app
