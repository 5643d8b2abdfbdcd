// `ltmsim features DIR`: recomputes DIR/features.exr and DIR/features/*.png from DIR/ltm.npz
// (and DIR/reference.exr for the deflection map) without tracing; with --pattern also the camera
// images y = T x of display patterns:
//   --pattern IMAGE (one PNG or EXR)      DIR/pattern.exr, channel "Image";
//   several --pattern, or any .npy stack  DIR/patterns.exr, one channel per pattern, and
//                                         DIR/patterns.npz: "images" float32 (K, rows, columns),
//                                         "names" (K,) bytes, in the order the patterns were given.
// A .npy stack is float32 or float64 of shape (K, P, Q) in display pixel order; its patterns are
// named STEM.j (j zero-padded to the digits of K - 1), an image's after its file's stem. All the
// patterns go through T in one pass (features/BlockProduct.h), whatever their number.

#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "app/Commands.h"
#include "app/FeatureOutputs.h"
#include "features/BlockProduct.h"
#include "io/Image.h"
#include "io/LtmFile.h"
#include "io/Npy.h"
#include "io/Npz.h"

namespace ltm::app {

namespace fs = std::filesystem;

namespace {

struct FeaturesArgs {
    std::string dir;
    std::vector<std::string> patterns;  // --pattern, in the order given
    FeatureOptions options{0.0, 0.99, -1};  // dark block -1: automatic (write_features)
    int threads = 0;
};

// One display pattern: the file it came from, its output channel's name, its P Q values in
// display pixel order (l = p Q + q), and whether it is one of a .npy stack's.
struct Pattern {
    std::string file, name;
    std::vector<float> values;
    bool from_stack = false;
};

// Every value finite: a NaN or an infinity would make the camera image NaN or infinite wherever
// the pattern's pixel is seen, silently; it is bad input instead.
void check_finite(const Pattern& x, const std::string& what, const DisplayGrid& d) {
    for (std::size_t l = 0; l < x.values.size(); ++l)
        if (!std::isfinite(x.values[l]))
            throw std::runtime_error(fmt::format("{}: {} has the value {} at display pixel (p, q) = ({}, {}); a pattern must "
                                                 "be finite",
                                                 x.file, what, x.values[l], l / static_cast<std::size_t>(d.Q),
                                                 l % static_cast<std::size_t>(d.Q)));
}

// The patterns of every --pattern file, checked against the display (size, shape, finiteness,
// distinct names). Throws std::runtime_error naming the file.
std::vector<Pattern> read_patterns(const std::vector<std::string>& files, const DisplayGrid& d) {
    std::vector<Pattern> out;
    for (const std::string& file : files) {
        const std::string stem = fs::path(file).stem().string();
        if (io::is_npy_file(file)) {
            const io::NpyFloatArray a = io::read_npy_floats(file);
            const auto& s = a.shape;
            if (s.size() != 3 || s[1] != static_cast<std::uint64_t>(d.P) || s[2] != static_cast<std::uint64_t>(d.Q))
                throw std::runtime_error(fmt::format("{}: the stack has shape {} but this display needs (K, {}, {}): K "
                                                     "patterns of P = {} rows and Q = {} columns",
                                                     file, io::npy_shape_repr(s), d.P, d.Q, d.P, d.Q));
            if (s[0] == 0) throw std::runtime_error(fmt::format("{}: the stack holds no patterns (shape {})", file, io::npy_shape_repr(s)));
            const std::size_t n = static_cast<std::size_t>(d.P) * static_cast<std::size_t>(d.Q);
            const int digits = static_cast<int>(std::to_string(s[0] - 1).size());
            for (std::uint64_t j = 0; j < s[0]; ++j) {
                Pattern x{file, fmt::format("{}.{:0{}}", stem, j, digits),
                          std::vector<float>(a.values.begin() + static_cast<std::ptrdiff_t>(j * n),
                                             a.values.begin() + static_cast<std::ptrdiff_t>((j + 1) * n)),
                          true};
                check_finite(x, fmt::format("pattern {}", j), d);
                out.push_back(std::move(x));
            }
        } else {
            const Image img = read_image(file);
            if (img.width != d.Q || img.height != d.P)
                throw std::runtime_error(fmt::format("{}: the pattern is {} x {} pixels but the display is {} x {}", file,
                                                     img.width, img.height, d.Q, d.P));
            Pattern x{file, stem, pattern_values(img)};
            check_finite(x, "the pattern", d);
            out.push_back(std::move(x));
        }
    }
    std::map<std::string, const Pattern*> seen;
    for (const Pattern& x : out) {
        const auto [it, fresh] = seen.emplace(x.name, &x);
        if (fresh) continue;
        if (x.file == it->second->file)
            throw std::runtime_error(fmt::format("{}: given twice (its output channel would be named '{}' twice)", x.file, x.name));
        throw std::runtime_error(fmt::format("{}: its pattern's output channel would be named '{}', as {}'s is: rename "
                                             "one of the files",
                                             x.file, x.name, it->second->file));
    }
    return out;
}

// The camera images of all patterns, Y = T X in one pass: X pixel-major (features/BlockProduct.h),
// each image then rounded to float as pattern.exr stores it.
std::vector<std::vector<float>> camera_images(const CsrMatrix& T, std::vector<Pattern>& patterns, int threads) {
    const std::size_t K = patterns.size(), n = static_cast<std::size_t>(T.cols);
    // The transpose in tiles of kTile display pixels: a tile of X (kTile K floats, 16 kB for
    // K = 64) stays in cache while each pattern's run of it is read in order. Column by column
    // over all of X, every store would miss the cache: most of a K = 64 call's own time.
    constexpr std::size_t kTile = 64;
    std::vector<float> X(n * K);
    for (std::size_t l0 = 0; l0 < n; l0 += kTile) {
        const std::size_t l1 = std::min(n, l0 + kTile);
        for (std::size_t j = 0; j < K; ++j) {
            const float* x = patterns[j].values.data();
            for (std::size_t l = l0; l < l1; ++l) X[l * K + j] = x[l];
        }
    }
    for (Pattern& x : patterns) std::vector<float>().swap(x.values);  // the block holds them now
    const std::vector<double> Y = multiply_block(T, X, static_cast<int>(K), threads);
    std::vector<std::vector<float>> images(K, std::vector<float>(static_cast<std::size_t>(T.rows)));
    for (std::size_t k = 0; k < static_cast<std::size_t>(T.rows); ++k)
        for (std::size_t j = 0; j < K; ++j) images[j][k] = static_cast<float>(Y[k * K + j]);
    return images;
}

// DIR/patterns.exr (channel per pattern) and DIR/patterns.npz ("images" (K, rows, columns)
// float32, "names" (K,) byte strings as long as the longest name, NUL-padded as numpy pads them).
void write_pattern_stack(const std::string& dir, const RenderGeometry& g, const std::vector<Pattern>& patterns,
                         const std::vector<std::vector<float>>& images) {
    std::vector<std::pair<std::string, std::vector<float>>> channels;
    std::vector<float> stack;
    std::size_t longest = 1;
    for (std::size_t j = 0; j < patterns.size(); ++j) {
        channels.emplace_back(patterns[j].name, images[j]);
        stack.insert(stack.end(), images[j].begin(), images[j].end());
        longest = std::max(longest, patterns[j].name.size());
    }
    std::string names(longest * patterns.size(), '\0');
    for (std::size_t j = 0; j < patterns.size(); ++j) names.replace(j * longest, patterns[j].name.size(), patterns[j].name);
    write_exr((fs::path(dir) / "patterns.exr").string(), g.camera_columns, g.camera_rows, channels);
    const auto K = static_cast<std::uint64_t>(patterns.size());
    io::write_npz((fs::path(dir) / "patterns.npz").string(),
                  {io::npy_array("images", stack, {K, static_cast<std::uint64_t>(g.camera_rows),
                                                   static_cast<std::uint64_t>(g.camera_columns)}),
                   io::NpyArray{"names", "|S" + std::to_string(longest), {K}, names.data(), names.size(), {}}});
}

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
    std::vector<Pattern> patterns;
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
        patterns = read_patterns(a.patterns, g.display);
    } catch (const std::exception& e) {
        std::cerr << "ltmsim features: " << e.what() << "\n";
        return 2;
    }
    // One image file alone gives DIR/pattern.exr with channel "Image"; anything else (several
    // patterns, or a stack of any size) is a stack.
    const bool single = patterns.size() == 1 && !patterns[0].from_stack;
    write_features(a.dir, T, g, a.options, reference ? &*reference : nullptr);
    if (patterns.empty()) return 0;
    const std::vector<std::vector<float>> images = camera_images(T, patterns, a.threads);
    if (single)
        write_exr((fs::path(a.dir) / "pattern.exr").string(), g.camera_columns, g.camera_rows, {{"Image", images[0]}});
    else
        write_pattern_stack(a.dir, g, patterns, images);
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
    cmd->add_option("--dark-block", args->options.dark_block, "DarkField: side of the centred block switched off, display pixels (default: 60, or the display's smaller side if less)")
        ->check(whole_number(0, kMaxInt));
    cmd->add_option("--pattern", args->patterns,
                    "A display pattern (PNG or EXR image) or a stack of them (.npy, float32/64, shape (K, P, Q)); "
                    "repeatable. One image: pattern.exr (channel Image) with the camera image y = T x; otherwise "
                    "patterns.exr (a channel per pattern) and patterns.npz (images: K x rows x columns)")
        ->expected(1)
        ->allow_extra_args(false)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    add_threads_option(cmd, args->threads, "Threads (default: all cores)");
    cmd->callback([args] { run_guarded("features", args->threads, [&] { return run(*args); }); });
}

}  // namespace ltm::app
