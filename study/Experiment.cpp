#include "study/Experiment.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <map>

#include "features/Plot.h"
#include "io/InputError.h"
#include "scene/SceneLoader.h"
#include "scene/SceneSolid.h"
#include "scene/StrictYaml.h"
#include "study/GroundTruth.h"

namespace ltm {

namespace fs = std::filesystem;

ExperimentSpec load_experiment(const std::string& path) {
    const YAML::Node root = yaml::load_document(path, "experiment file");
    const yaml::Reader r(path);
    ExperimentSpec e;
    e.file = path;
    e.folder = fs::path(path).parent_path().string();
    if (!root.IsMap())
        r.fail(yaml::loc_of(root), "", fmt::format("expected a mapping with scenes, reference and montage, got {}", yaml::describe(root)));
    auto word = [&](const YAML::Node& v, yaml::Loc at, const std::string& p) {
        if (!v.IsScalar() || v.Scalar().empty()) r.fail(at, p, fmt::format("expected a name, got {}", yaml::describe(v)));
        return v.Scalar();
    };
    auto words = [&](const yaml::Item& it, const std::string& p) {
        if (!it.value.IsSequence())
            r.fail(it.value_loc(), p, fmt::format("expected a list of channel names, got {}", yaml::describe(it.value)));
        std::vector<std::string> out;
        for (std::size_t i = 0; i < it.value.size(); ++i)
            out.push_back(word(it.value[i], yaml::loc_of(it.value[i]), fmt::format("{}[{}]", p, i)));
        return out;
    };
    yaml::KeyRule rule;
    rule.keys = {"scenes", "reference", "montage", "candidates", "defect_fraction"};
    yaml::Where seen;
    r.walk(root, "", rule, [&](const yaml::Item& it) {
        seen[it.key] = it.value_loc();
        if (it.key == "scenes") {
            if (!it.value.IsSequence() || it.value.size() == 0)
                r.fail(it.value_loc(), "scenes", fmt::format("expected a list of {{file, label}}, got {}", yaml::describe(it.value)));
            for (std::size_t i = 0; i < it.value.size(); ++i) {
                const YAML::Node n = it.value[i];
                const std::string p = fmt::format("scenes[{}]", i);
                if (!n.IsMap()) r.fail(yaml::loc_of(n), p, fmt::format("expected {{file: ..., label: ...}}, got {}", yaml::describe(n)));
                yaml::KeyRule sr;
                sr.keys = {"file", "label"};
                std::string file, label;
                yaml::Where got;
                r.walk(n, p, sr, [&](const yaml::Item& x) {
                    got[x.key] = x.value_loc();
                    (x.key == "file" ? file : label) = word(x.value, x.value_loc(), yaml::join_path(p, x.key));
                });
                r.require_keys(n, p, got, {"file", "label"});
                e.scenes.emplace_back(file, label);
            }
        } else if (it.key == "reference") {
            e.reference = word(it.value, it.value_loc(), "reference");
        } else if (it.key == "montage") {
            e.montage = words(it, "montage");
        } else if (it.key == "candidates") {
            e.candidates = words(it, "candidates");
        } else if (it.key == "defect_fraction") {
            e.defect_fraction = r.number(it.value, it.value_loc(), "defect_fraction");
            if (!(e.defect_fraction > 0 && e.defect_fraction <= 1))
                r.fail(it.value_loc(), "defect_fraction", fmt::format("must be in (0, 1], got {}", e.defect_fraction));
        }
    });
    r.require_keys(root, "", seen, {"scenes", "reference", "montage"});
    bool listed = false;
    for (const auto& [file, label] : e.scenes) listed = listed || file == e.reference;
    if (!listed) r.fail(seen.at("reference"), "reference", fmt::format("'{}' is not one of the scenes", e.reference));
    return e;
}

std::vector<ExperimentScene> load_experiment_scenes(const ExperimentSpec& spec) {
    std::vector<ExperimentScene> out;
    for (const auto& [file, label] : spec.scenes) {
        ExperimentScene s;
        s.file = file;
        s.label = label;
        s.stem = fs::path(file).stem().string();
        const std::string path = (fs::path(spec.folder) / file).string();
        s.scene = load_scene(path);
        try {
            s.solid = build_solid(s.scene, nullptr, /*surfaces_only=*/true);
        } catch (const std::invalid_argument& e) {
            throw std::invalid_argument(fmt::format("{}: {}", path, e.what()));
        }
        out.push_back(std::move(s));
    }
    return out;
}

void render_experiment_scene(ExperimentScene& s, int threads, ReferenceCache* cache) {
    SceneRunOptions o;
    o.reference_cache = cache;
    o.representation = auto_representation(s.solid);
    o.threads = threads;
    s.run = run_scene(s.scene, s.solid, o, nullptr);
}

Region traced_defect_region(const Scene& scene, const RenderResult& render, int defect, double min_fraction) {
    const GroundTruth g = ground_truth(scene, render, min_fraction);
    Region r;
    for (size_t k = 0; k < g.mask.size(); ++k)
        if (g.mask[k] == defect + 1) r.pixels.push_back(static_cast<int>(k));
    return r;
}

Region pixels_meeting_defects(const RenderResult& render) {
    Region r;
    for (const DefectPaths& e : render.defect_paths)
        if (r.pixels.empty() || r.pixels.back() != e.pixel) r.pixels.push_back(e.pixel);
    return r;
}

namespace {

// The smallest rho^2 of the defect's ellipsoid grown by `grow` mm along each semi-axis, over the
// polyline of a principal path.
double min_rho2_along(const PrincipalPath& p, const Vec3& start, const Defect& d, double grow) {
    Defect g = d;
    g.semi_axes = d.semi_axes + Vec3{grow, grow, grow};
    Vec3 prev = start;
    double m = INFINITY;
    for (size_t i = 0; i <= p.vertices.size(); ++i) {
        const Vec3 next = i < p.vertices.size() ? p.vertices[i] : prev + p.direction * 1e3;
        m = std::min(m, g.segment_min_rho2(prev, next));
        prev = next;
    }
    return m;
}

bool in_aperture(const Scene& s, const Vec3& c) { return std::hypot(c.x, c.y) <= 0.95 * 0.5 * s.object.lens.diameter; }

// The geometric surround shell of defect d (see Experiment.h).
Region surround_shell(const Tracer& free, const Scene& scene, const Defect& d) {
    const double pitch = scene.camera.size[0] / scene.camera.resolution[0];
    const double rmin = std::min({d.semi_axes.x, d.semi_axes.y, d.semi_axes.z});
    const double inner = 2 * rmin + 2 * pitch, outer = 5 * rmin + 4 * pitch;
    Region reg;
    for (long k = 0; k < free.camera().pixels(); ++k) {
        const Vec3 c = free.camera().pixel_centre(k);
        if (!in_aperture(scene, c)) continue;
        const Vec3 start{c.x, c.y, -1e3};
        const PrincipalPath p = free.principal_path(start, {0, 0, 1});
        if (min_rho2_along(p, start, d, outer) <= 1.0 && min_rho2_along(p, start, d, inner) > 1.0)
            reg.pixels.push_back(static_cast<int>(k));
    }
    return reg;
}

}  // namespace

std::vector<DefectRegions> experiment_regions(const ExperimentSpec& spec, const ExperimentScene& r) {
    std::vector<DefectRegions> out;
    const Scene& scene = r.scene;
    if (scene.defects.empty()) return out;
    const Scene free_scene = defect_free(scene);
    const Solid free_solid = build_solid(free_scene, nullptr, /*surfaces_only=*/true);
    TracerOptions fo;
    fo.representation = Representation::Analytic;
    const Tracer free(free_scene, free_solid, fo);
    const Region met = pixels_meeting_defects(r.run.render);
    for (size_t k = 0; k < scene.defects.size(); ++k) {
        const Defect& d = scene.defects[k];
        DefectRegions g;
        g.defect = static_cast<int>(k);
        g.radius_mm = d.max_semi_axis();
        g.defect_pixels = traced_defect_region(scene, r.run.render, static_cast<int>(k), spec.defect_fraction);
        auto& px = g.defect_pixels.pixels;
        px.erase(std::remove_if(px.begin(), px.end(), [&](int p) { return !in_aperture(scene, free.camera().pixel_centre(p)); }),
                 px.end());
        g.surround = subtract(surround_shell(free, scene, d), met);
        out.push_back(std::move(g));
    }
    return out;
}

io::Json regions_json(const std::vector<DefectRegions>& regions) {
    io::Json defects = io::Json::array();
    for (const DefectRegions& g : regions)
        defects.push_back({{"defect", g.defect}, {"radius_mm", g.radius_mm}, {"defect_pixels", g.defect_pixels.pixels},
                           {"surround_pixels", g.surround.pixels}});
    return {{"defects", defects}};
}

std::vector<DefectRegions> read_regions_json(const std::string& path, long pixels) {
    const io::Json j = io::read_json_file(path, "regions file");
    auto fail = [&](const std::string& what) -> void {
        throw InputError(path, 0, 0, "", what);
    };
    if (!j.is_object() || !j.contains("defects") || !j["defects"].is_array()) fail("expected an object with a list 'defects'");
    std::vector<DefectRegions> out;
    for (std::size_t i = 0; i < j["defects"].size(); ++i) {
        const io::Json& d = j["defects"][i];
        const std::string at = fmt::format("defects[{}]", i);
        if (!d.is_object()) fail(at + ": expected an object");
        DefectRegions g;
        for (const char* key : {"defect", "radius_mm", "defect_pixels", "surround_pixels"})
            if (!d.contains(key)) fail(fmt::format("{}: missing key '{}'", at, key));
        if (!d["defect"].is_number_integer() || !d["radius_mm"].is_number()) fail(at + ": defect must be an integer, radius_mm a number");
        g.defect = d["defect"].get<int>();
        g.radius_mm = d["radius_mm"].get<double>();
        for (const char* key : {"defect_pixels", "surround_pixels"}) {
            const io::Json& a = d[key];
            if (!a.is_array()) fail(fmt::format("{}.{}: expected a list of pixel indices", at, key));
            Region& reg = std::string(key) == "defect_pixels" ? g.defect_pixels : g.surround;
            for (std::size_t e = 0; e < a.size(); ++e) {
                if (!a[e].is_number_integer() || a[e].get<long>() < 0 || a[e].get<long>() >= pixels)
                    fail(fmt::format("{}.{}[{}]: expected a camera pixel index in [0, {})", at, key, e, pixels));
                reg.pixels.push_back(a[e].get<int>());
            }
        }
        out.push_back(std::move(g));
    }
    return out;
}

ExperimentResult evaluate_experiment(const ExperimentSpec& spec, const std::vector<ExperimentScene>& runs) {
    ExperimentResult out;
    std::vector<std::string> channels;
    for (const auto& r : runs)
        for (const auto& [name, v] : r.run.features.channels)
            if (std::find(channels.begin(), channels.end(), name) == channels.end()) channels.push_back(name);
    std::string csv = "scene,defect,radius_mm,channel,defect_mean,surround_mean,surround_std,cnr,defect_pixels,surround_pixels\n";
    std::map<std::string, std::vector<double>> smallest_cnr;  // channel -> CNRs of the smallest defects
    double smallest_radius = INFINITY;
    for (const auto& r : runs)
        for (const auto& d : r.scene.defects) smallest_radius = std::min(smallest_radius, d.max_semi_axis());
    std::vector<std::string> md_columns;
    std::map<std::string, std::vector<double>> md_rows;
    for (const auto& r : runs) {
        out.regions.push_back(experiment_regions(spec, r));
        const std::vector<DefectRegions>& regions = out.regions.back();
        for (const DefectRegions& g : regions) {
            const int k = g.defect;
            md_columns.push_back(fmt::format("{} #{}", r.label, k));
            for (const auto& ch : channels) {
                if (!r.run.features.has(ch)) continue;
                ContrastResult c;
                if (g.defect_pixels.pixels.size() >= 2 && g.surround.pixels.size() >= 2)
                    c = contrast_to_noise(r.run.features.channel(ch), g.defect_pixels, g.surround);
                else
                    c.cnr = NAN;  // the defect is not seen at this resolution
                csv += fmt::format("{},{},{},{},{},{},{},{},{},{}\n", r.stem, k, g.radius_mm, ch, c.defect_mean,
                                   c.surround_mean, c.surround_std, c.cnr, c.defect_pixels, c.surround_pixels);
                md_rows[ch].push_back(c.cnr);
                if (g.radius_mm == smallest_radius) smallest_cnr[ch].push_back(c.cnr);
            }
        }
    }
    // False positives of the reference scene, within 0.95 of the clear aperture.
    std::map<std::string, int> false_pos;
    for (const auto& r : runs) {
        if (r.file != spec.reference) continue;
        const Scene& s = r.scene;
        Region valid;
        const TelecentricCamera camera(s.camera, 0.0);
        for (long k = 0; k < camera.pixels(); ++k)
            if (in_aperture(s, camera.pixel_centre(k))) valid.pixels.push_back(static_cast<int>(k));
        for (const auto& ch : channels) {
            if (!r.run.features.has(ch)) continue;
            false_pos[ch] = false_positives(r.run.features.channel(ch), valid);
            csv += fmt::format("{},,,{},,,,,,false_positives={}\n", r.stem, ch, false_pos[ch]);
        }
    }
    // The best new feature: among the candidates with the fewest false positives in the
    // reference scene, the one whose weakest smallest-defect CNR is largest (an infinite CNR, from
    // a noise-free surround, ranks above any finite one; a defect not seen ranks lowest).
    int best_fp = INT32_MAX;
    double best_cnr = -1;
    for (const auto& ch : spec.candidates) {
        const auto it = smallest_cnr.find(ch);
        if (it == smallest_cnr.end() || it->second.empty()) continue;
        const int fp = false_pos.count(ch) ? false_pos[ch] : 0;
        double weakest = INFINITY;
        for (double c : it->second) weakest = std::min(weakest, std::isnan(c) ? -1.0 : c);
        if (fp < best_fp || (fp == best_fp && weakest > best_cnr)) {
            best_fp = fp;
            best_cnr = weakest;
            out.best = ch;
        }
    }
    std::string md = fmt::format(
        "# Contrast-to-noise ratio of every defect in every image\n\nCNR = |mean(defect) - mean(surround)| / "
        "std(surround). Defect: the pixels at least {:g} of whose paths meet the defect first (traced); surround: the "
        "shell 2r + 2 px .. 5r + 4 px beyond the defect's ellipsoid (r its smallest semi-axis) along the defect-free "
        "object's centre rays, minus every pixel a path of which met a defect. False positives: defect-free pixels "
        "within 0.95 of the aperture more than 5 x 1.4826 MAD from the median. Best new feature (fewest false positives, "
        "then the largest weakest CNR over the smallest defects): **{}**.\n\n| image |",
        spec.defect_fraction, out.best);
    for (const auto& c : md_columns) md += " " + c + " |";
    md += " false positives (defect-free) |\n|---|";
    for (size_t i = 0; i <= md_columns.size(); ++i) md += "---|";
    md += "\n";
    for (const auto& ch : channels) {
        if (md_rows[ch].empty()) continue;
        md += "| " + ch + " |";
        for (double c : md_rows[ch]) md += std::isnan(c) ? std::string(" not seen |") : fmt::format(" {:.3g} |", c);
        md += fmt::format(" {} |\n", false_pos.count(ch) ? std::to_string(false_pos[ch]) : "");
    }
    out.csv = std::move(csv);
    out.markdown = std::move(md);

    // The montage: rows are images, columns are scenes.
    std::vector<std::string> rows = spec.montage;
    if (!out.best.empty()) rows.push_back(out.best);
    std::vector<std::vector<Image>> cells;
    std::vector<std::string> col_labels;
    for (const auto& r : runs) col_labels.push_back(r.label);
    std::vector<std::string> row_labels;
    for (const auto& ch : rows) {
        std::vector<Image> row;
        for (const auto& r : runs)
            row.push_back(r.run.features.has(ch)
                              ? pseudo_colour(r.run.features.channel(ch), r.run.features.width, r.run.features.height, "",
                                              NAN, NAN, std::max(1, 300 / r.run.features.width),
                                              {r.scene.camera.size[0], r.scene.camera.size[1]})
                              : Image{});
        cells.push_back(std::move(row));
        row_labels.push_back(feature_title(ch));
    }
    out.montage = montage(cells, row_labels, col_labels, "Simulated inspection images (columns: scenes; rows: images)");
    return out;
}

}  // namespace ltm
