// `ltmsim experiment FOLDER -o OUT`: renders every scene an experiment file lists, computes their
// features, and puts numbers on them: the contrast-to-noise ratio of every defect in every image
// against the defect-free surround of the same scene, and the false-positive pixels of the
// defect-free scene. Writes OUT/<scene>/ (as `render`), OUT/contrast.csv, OUT/contrast.md and
// OUT/montage.png (rows: images, columns: scenes), as the paper's Fig. 3.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <map>

#include "app/Commands.h"
#include "app/FeatureOutputs.h"
#include "app/SceneSetup.h"
#include "features/Contrast.h"
#include "features/Image.h"
#include "features/Plot.h"
#include "io/AtomicFile.h"
#include "scene/SceneSolid.h"
#include "trace/LtmFile.h"
#include "trace/Render.h"

namespace ltm::app {

namespace fs = std::filesystem;

namespace {

struct ExperimentArgs {
    std::string folder, out;
    int threads = 0;
    bool overwrite = false;
};

struct ExperimentFile {
    std::vector<std::pair<std::string, std::string>> scenes;  // file, label
    std::string reference;
    std::vector<std::string> montage, candidates;
};

// experiment.yaml: scenes (file, label), reference (the defect-free scene), montage (image rows),
// candidates (new features competing for the montage's last row). Strict: unknown keys are errors.
ExperimentFile read_experiment(const std::string& path) {
    YAML::Node root;
    try {
        root = YAML::LoadFile(path);
    } catch (const YAML::Exception& e) {
        throw std::runtime_error(fmt::format("{}:{}:{}: {}", path, e.mark.line + 1, e.mark.column + 1, e.msg));
    }
    auto at = [&](const YAML::Node& n, const std::string& key) {
        return fmt::format("{}:{}:{}: {}", path, n.Mark().line + 1, n.Mark().column + 1, key);
    };
    ExperimentFile f;
    if (!root.IsMap()) throw std::runtime_error(path + ": expected a mapping");
    for (const auto& kv : root) {
        const std::string key = kv.first.as<std::string>();
        const YAML::Node& v = kv.second;
        if (key == "scenes") {
            if (!v.IsSequence()) throw std::runtime_error(at(v, "scenes: expected a list"));
            for (size_t i = 0; i < v.size(); ++i) {
                if (!v[i].IsMap() || !v[i]["file"] || !v[i]["label"] || v[i].size() != 2)
                    throw std::runtime_error(at(v[i], fmt::format("scenes[{}]: expected {{file: ..., label: ...}}", i)));
                f.scenes.emplace_back(v[i]["file"].as<std::string>(), v[i]["label"].as<std::string>());
            }
        } else if (key == "reference") {
            f.reference = v.as<std::string>();
        } else if (key == "montage" || key == "candidates") {
            if (!v.IsSequence()) throw std::runtime_error(at(v, key + ": expected a list of channel names"));
            for (const auto& x : v) (key == "montage" ? f.montage : f.candidates).push_back(x.as<std::string>());
        } else {
            throw std::runtime_error(at(kv.first, fmt::format("unknown key '{}'; valid keys are: scenes, reference, montage, candidates", key)));
        }
    }
    if (f.scenes.empty() || f.reference.empty() || f.montage.empty())
        throw std::runtime_error(path + ": needs scenes, reference and montage");
    return f;
}

struct Rendered {
    LoadedScene loaded;
    FeatureImages features;
    std::string label, stem;
};

// Renders one scene as `ltmsim render` does (reference pass included) into out/stem.
Rendered render_scene(const std::string& file, const std::string& label, const std::string& out, int threads) {
    StageReport report;
    int status = 0;
    auto loaded = load_scene_and_solid(file, report, status, /*surfaces_only=*/true);
    if (!loaded) throw std::invalid_argument("bad scene " + file);
    Rendered r;
    r.label = label;
    r.stem = fs::path(file).stem().string();
    const Scene& scene = loaded->scene;
    TracerOptions topt;
    std::string why;
    topt.representation = Tracer::analytic_supported(loaded->solid, &why) ? Representation::Analytic : Representation::Refined;
    const Tracer tracer(scene, loaded->solid, topt);
    RenderOptions ro;
    ro.threads = threads;
    const RenderResult res = render(tracer, ro);
    const std::vector<float> reference = defect_free_reference(scene, res.T, topt.representation, ro);
    r.features = write_render_folder((fs::path(out) / r.stem).string(), scene, res, topt.representation, threads,
                                     FeatureOptions{0.0, 0.99, -1}, reference, report);
    r.loaded = std::move(*loaded);
    return r;
}

// The smallest of rho^2 = |S^-1 F^T (x - c)|^2 over the segment [a, b], for the ellipsoid with
// centre c, frame F and semi-axes e: rho^2 is a quadratic in the segment's parameter, minimal at its
// vertex (clamped to the segment).
double min_rho2(const Vec3& a, const Vec3& b, const Vec3& c, const Mat3& F, const Vec3& e) {
    const Mat3 Ft = F.transposed();
    const Vec3 ya = Ft * (a - c), yd = Ft * (b - a);
    const Vec3 u{ya.x / e.x, ya.y / e.y, ya.z / e.z}, v{yd.x / e.x, yd.y / e.y, yd.z / e.z};
    const double vv = dot(v, v);
    const double t = vv > 0 ? std::clamp(-dot(u, v) / vv, 0.0, 1.0) : 0.0;
    return length2(u + v * t);
}

// Camera pixels whose centre ray (axial, through the defect-free object) passes within the
// defect's ellipsoid grown by `outer` mm along each semi-axis but not within it grown by `inner`
// (inner < 0: no inner limit). For a sphere of radius r that is a distance from its centre in
// [r + inner, r + outer]; for an elongated one it follows its shape. Pixels outside 0.95 of the
// clear aperture are left out (the rim's own image is no defect).
Region pixels_near(const Tracer& free, const Scene& scene, const Defect& d, double inner, double outer) {
    Region reg;
    const int N = scene.camera.resolution[0], M = scene.camera.resolution[1];
    const double a = 0.5 * scene.object.lens.diameter;
    const Vec3 grow_out{outer, outer, outer}, grow_in{inner, inner, inner};
    for (int m = 0; m < M; ++m)
        for (int n = 0; n < N; ++n) {
            const long k = static_cast<long>(m) * N + n;
            const Vec3 c = free.camera().pixel_centre(k);
            if (std::hypot(c.x, c.y) > 0.95 * a) continue;
            const PrincipalPath p = free.principal_path({c.x, c.y, -1e3}, {0, 0, 1});
            Vec3 prev{c.x, c.y, -1e3};
            double out2 = INFINITY, in2 = INFINITY;
            for (size_t i = 0; i <= p.vertices.size(); ++i) {
                const Vec3 next = i < p.vertices.size() ? p.vertices[i] : prev + p.direction * 1e3;
                out2 = std::min(out2, min_rho2(prev, next, d.center, d.frame, d.semi_axes + grow_out));
                if (inner >= 0) in2 = std::min(in2, min_rho2(prev, next, d.center, d.frame, d.semi_axes + grow_in));
                prev = next;
            }
            if (out2 <= 1.0 && (inner < 0 || in2 > 1.0)) reg.pixels.push_back(k);
        }
    return reg;
}

int run(const ExperimentArgs& a) {
    ExperimentFile exp;
    const std::string exp_path = (fs::path(a.folder) / "experiment.yaml").string();
    try {
        exp = read_experiment(exp_path);
    } catch (const std::exception& e) {
        std::cerr << e.what() << "\n";
        return 2;
    }
    if (!output_folder_ok("experiment", a.out)) return 2;
    if (!a.overwrite && fs::exists(fs::path(a.out) / "contrast.csv")) {
        std::cerr << fmt::format("ltmsim experiment: {} holds results; pass --overwrite to replace them\n", a.out);
        return 2;
    }
    // Load every scene first, so a bad one stops the run before anything is rendered.
    for (const auto& [file, label] : exp.scenes) {
        StageReport report;
        int status = 0;
        if (!load_scene_and_solid((fs::path(a.folder) / file).string(), report, status)) return status;
    }
    fs::create_directories(a.out);
    std::vector<Rendered> runs;
    for (const auto& [file, label] : exp.scenes) {
        std::cerr << fmt::format("rendering {} ({})\n", file, label);
        runs.push_back(render_scene((fs::path(a.folder) / file).string(), label, a.out, a.threads));
    }

    // Contrast of every defect in every image.
    // Every channel any scene has (scenes with defects also have the deflection map).
    std::vector<std::string> channels;
    for (const auto& r : runs)
        for (const auto& [name, v] : r.features.channels)
            if (std::find(channels.begin(), channels.end(), name) == channels.end()) channels.push_back(name);
    std::string csv = "scene,defect,radius_mm,channel,defect_mean,surround_mean,surround_std,cnr,defect_pixels,surround_pixels\n";
    std::map<std::string, std::vector<double>> smallest_cnr;  // channel -> CNRs of the smallest bubbles
    double smallest_radius = INFINITY;
    for (const auto& r : runs)
        for (const auto& d : r.loaded.scene.defects) smallest_radius = std::min(smallest_radius, d.max_semi_axis());
    std::vector<std::string> md_columns;
    std::map<std::string, std::vector<double>> md_rows;
    for (const auto& r : runs) {
        const Scene& scene = r.loaded.scene;
        if (scene.defects.empty()) continue;
        const Scene free_scene = defect_free(scene);
        const Solid free_solid = build_solid(free_scene, nullptr, /*surfaces_only=*/true);
        TracerOptions fo;
        fo.representation = Representation::Analytic;
        const Tracer free(free_scene, free_solid, fo);
        const double pitch = scene.camera.size[0] / scene.camera.resolution[0];
        std::vector<Region> defect_regions;
        // The defect's image: its ellipsoid grown by half a pixel's diagonal. The surround: the
        // shell 2 r + 2 px .. 5 r + 4 px beyond it, r the smallest semi-axis (for a sphere, 3 r + 2 px
        // .. 6 r + 4 px from its centre).
        for (const auto& d : scene.defects)
            defect_regions.push_back(pixels_near(free, scene, d, -1.0, 0.5 * pitch * std::sqrt(2.0)));
        for (size_t k = 0; k < scene.defects.size(); ++k) {
            const Defect& d = scene.defects[k];
            const double rr = d.max_semi_axis(), rmin = std::min({d.semi_axes.x, d.semi_axes.y, d.semi_axes.z});
            Region surround = pixels_near(free, scene, d, 2 * rmin + 2 * pitch, 5 * rmin + 4 * pitch);
            for (const auto& other : defect_regions) surround = subtract(surround, other);
            md_columns.push_back(fmt::format("{} #{}", r.label, k));
            for (const auto& ch : channels) {
                if (!r.features.has(ch)) continue;
                const ContrastResult c = contrast_to_noise(r.features.channel(ch), defect_regions[k], surround);
                csv += fmt::format("{},{},{},{},{},{},{},{},{},{}\n", r.stem, k, rr, ch, c.defect_mean, c.surround_mean,
                                   c.surround_std, c.cnr, c.defect_pixels, c.surround_pixels);
                md_rows[ch].push_back(c.cnr);
                if (rr == smallest_radius) smallest_cnr[ch].push_back(c.cnr);
            }
        }
    }
    // False positives of the defect-free scene, within 0.95 of the clear aperture.
    std::map<std::string, int> false_pos;
    for (const auto& r : runs) {
        if (fs::path(exp.reference).stem().string() != r.stem) continue;
        const Scene& s = r.loaded.scene;
        Region valid;
        const TelecentricCamera camera(s.camera, 0.0);
        for (long k = 0; k < camera.pixels(); ++k) {
            const Vec3 c = camera.pixel_centre(k);
            if (std::hypot(c.x, c.y) <= 0.95 * 0.5 * s.object.lens.diameter) valid.pixels.push_back(k);
        }
        for (const auto& ch : channels) {
            // The deflection map is defined against the defect-free object itself: zero there.
            if (!r.features.has(ch)) continue;
            false_pos[ch] = false_positives(r.features.channel(ch), valid);
            csv += fmt::format("{},,,{},,,,,,false_positives={}\n", r.stem, ch, false_pos[ch]);
        }
    }
    // The best new feature: among the candidates with the fewest false positives in the
    // defect-free scene, the one whose weakest smallest-bubble CNR is largest (an infinite CNR,
    // from a noise-free surround, ranks above any finite one).
    std::string best;
    int best_fp = INT32_MAX;
    double best_cnr = -1;
    for (const auto& ch : exp.candidates) {
        const auto it = smallest_cnr.find(ch);
        if (it == smallest_cnr.end() || it->second.empty()) continue;
        const int fp = false_pos.count(ch) ? false_pos[ch] : 0;
        const double weakest = *std::min_element(it->second.begin(), it->second.end());
        if (fp < best_fp || (fp == best_fp && weakest > best_cnr)) {
            best_fp = fp;
            best_cnr = weakest;
            best = ch;
        }
    }
    std::string md = fmt::format("# Contrast-to-noise ratio of every defect in every image\n\nCNR = |mean(defect) - "
                                 "mean(surround)| / std(surround); surround: the annulus 3r + 2 px .. 6r + 4 px around "
                                 "the defect's image. False positives: defect-free pixels within 0.95 of the aperture more than 5 x 1.4826 MAD from the median. Best new feature (fewest false positives, then the largest weakest CNR over the smallest bubbles): **{}**.\n\n| image |",
                                 best);
    for (const auto& c : md_columns) md += " " + c + " |";
    md += " false positives (defect-free) |\n|---|";
    for (size_t i = 0; i <= md_columns.size(); ++i) md += "---|";
    md += "\n";
    for (const auto& ch : channels) {
        if (md_rows[ch].empty()) continue;
        md += "| " + ch + " |";
        for (double c : md_rows[ch]) md += fmt::format(" {:.3g} |", c);
        md += fmt::format(" {} |\n", false_pos.count(ch) ? std::to_string(false_pos[ch]) : "");
    }
    io::write_file((fs::path(a.out) / "contrast.csv").string(), csv, "contrast table");
    io::write_file((fs::path(a.out) / "contrast.md").string(), md, "contrast table");

    // The montage: rows are images, columns are scenes.
    std::vector<std::string> rows = exp.montage;
    if (!best.empty()) rows.push_back(best);
    std::vector<std::vector<Image>> cells;
    std::vector<std::string> col_labels;
    for (const auto& r : runs) col_labels.push_back(r.label);
    for (const auto& ch : rows) {
        std::vector<Image> row;
        for (const auto& r : runs)
            row.push_back(pseudo_colour(r.features.channel(ch), r.features.width, r.features.height, "", NAN, NAN,
                                        std::max(1, 300 / r.features.width)));
        cells.push_back(std::move(row));
    }
    write_png((fs::path(a.out) / "montage.png").string(),
              montage(cells, rows, col_labels, "Simulated inspection images (columns: scenes; rows: images)"));
    std::cout << md;
    return 0;
}

}  // namespace

void add_experiment_command(CLI::App& app) {
    auto args = std::make_shared<ExperimentArgs>();
    CLI::App* cmd = app.add_subcommand("experiment", "Render an experiment's scenes; contrast tables and a montage");
    cmd->add_option("folder", args->folder, "A folder with experiment.yaml and its scenes")->required();
    cmd->add_option("-o,--output", args->out, "Output folder")->required();
    cmd->add_option("--threads", args->threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
    cmd->add_flag("--overwrite", args->overwrite, "Replace earlier results in the output folder");
    cmd->callback([args] { run_guarded("experiment", [&] { return run(*args); }); });
}

}  // namespace ltm::app
