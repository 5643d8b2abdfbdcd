// `ltmsim features DIR`: recomputes DIR/features.exr and DIR/features/*.png from DIR/ltm.npz
// (and DIR/reference.exr for the deflection map) without tracing; with --pattern IMAGE also the
// camera image for that display pattern, y = T x, as DIR/pattern.exr.
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <sstream>

#include "app/Commands.h"
#include "app/FeatureOutputs.h"
#include "io/Image.h"
#include "io/LtmFile.h"

namespace ltm::app {

namespace fs = std::filesystem;

namespace {

struct FeaturesArgs {
    std::string dir, pattern;
    FeatureOptions options{0.0, 0.99, -1};  // dark block -1: automatic (write_features)
    int threads = 0;
};

int run(const FeaturesArgs& a) {
    // Everything is read and checked before anything is written.
    const fs::path npz = fs::path(a.dir) / "ltm.npz";
    if (!fs::is_regular_file(npz)) {
        std::cerr << fmt::format("ltmsim features: {}: no ltm.npz there (render it with ltmsim render SCENE -o {})\n",
                                 a.dir, a.dir);
        return 2;
    }
    if (!(a.options.threshold >= 0) || !std::isfinite(a.options.threshold)) {
        std::cerr << fmt::format("ltmsim features: --threshold must be a finite number >= 0 (got {})\n", a.options.threshold);
        return 2;
    }
    if (!(a.options.energy_fraction > 0 && a.options.energy_fraction <= 1)) {
        std::cerr << fmt::format("ltmsim features: --energy-fraction must be in (0, 1] (got {})\n", a.options.energy_fraction);
        return 2;
    }
    CsrMatrix T;
    RenderGeometry g;
    std::optional<std::vector<float>> reference;
    std::vector<float> pattern;
    try {
        T = read_ltm_npz(npz.string());
        g = read_render_geometry(a.dir);
        reference = read_reference(a.dir, g.camera_columns * g.camera_rows);
        if (T.rows != static_cast<std::int64_t>(g.camera_columns) * g.camera_rows ||
            T.cols != static_cast<std::int64_t>(g.display.P) * g.display.Q)
            throw std::runtime_error(fmt::format("{} is {} x {} but run.json describes a {} x {} camera and a {} x {} display",
                                                 npz.string(), T.rows, T.cols, g.camera_columns, g.camera_rows, g.display.Q,
                                                 g.display.P));
        if (a.options.dark_block < -1 || a.options.dark_block > std::min(g.display.P, g.display.Q))
            throw std::runtime_error(fmt::format("--dark-block must be in [0, {}] display pixels (got {})",
                                                 std::min(g.display.P, g.display.Q), a.options.dark_block));
        if (!a.pattern.empty()) {
            const Image img = read_image(a.pattern);
            if (img.width != g.display.Q || img.height != g.display.P)
                throw std::runtime_error(fmt::format("{}: the pattern is {} x {} pixels but the display is {} x {}",
                                                     a.pattern, img.width, img.height, g.display.Q, g.display.P));
            pattern = pattern_values(img);
        }
    } catch (const std::exception& e) {
        std::cerr << "ltmsim features: " << e.what() << "\n";
        return 2;
    }
    write_features(a.dir, T, g, a.options, reference ? &*reference : nullptr);
    if (!pattern.empty()) {
        const std::vector<double> y = apply_pattern(T, pattern);
        write_exr((fs::path(a.dir) / "pattern.exr").string(), g.camera_columns, g.camera_rows,
                  {{"Image", std::vector<float>(y.begin(), y.end())}});
    }
    return 0;
}

}  // namespace

void add_features_command(CLI::App& app) {
    auto args = std::make_shared<FeaturesArgs>();
    CLI::App* cmd = app.add_subcommand("features", "Recompute feature images from an existing DIR/ltm.npz");
    cmd->add_option("dir", args->dir, "A folder written by ltmsim render")->required();
    cmd->add_option("--threshold", args->options.threshold, "ScatterCount/Width count entries above this (default 0)");
    cmd->add_option("--energy-fraction", args->options.energy_fraction,
                    "Robust features keep the smallest set of display pixels holding this fraction (default 0.99)");
    cmd->add_option("--dark-block", args->options.dark_block, "DarkField: side of the centred block switched off, display pixels (default: 60, or the display's smaller side if less)");
    cmd->add_option("--pattern", args->pattern, "Also write pattern.exr: the camera image y = T x for this display pattern");
    cmd->add_option("--threads", args->threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
    cmd->callback([args] { run_guarded("features", [&] { return run(*args); }); });
}

}  // namespace ltm::app
