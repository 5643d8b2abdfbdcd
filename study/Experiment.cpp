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
#include "defects/ScratchPath.h"
#include "geometry/Lens.h"
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
    // Feature channels, each one compute_features makes (features/Features.h).
    const std::vector<std::string>& known = feature_channel_names(true);
    auto words = [&](const yaml::Item& it, const std::string& p) {
        if (!it.value.IsSequence())
            r.fail(it.value_loc(), p, fmt::format("expected a list of channel names, got {}", yaml::describe(it.value)));
        std::vector<std::string> out;
        for (std::size_t i = 0; i < it.value.size(); ++i) {
            const std::string at = fmt::format("{}[{}]", p, i);
            const std::string name = word(it.value[i], yaml::loc_of(it.value[i]), at);
            if (std::find(known.begin(), known.end(), name) == known.end()) {
                std::string list;
                for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
                r.fail(yaml::loc_of(it.value[i]), at, fmt::format("unknown feature channel '{}' (channels: {})", name, list));
            }
            out.push_back(name);
        }
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

// The distance between segments [p0, p1] and [q0, q1]: the closest points s, t in [0, 1] of the
// two lines, clamped and recomputed (C. Ericson, "Real-Time Collision Detection", 2005, 5.1.9).
double segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
    const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
    const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    double s = 0, t = 0;
    if (a <= 0 && e <= 0) return length(r);
    if (a <= 0) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = dot(d1, r);
        if (e <= 0) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = dot(d1, d2), denom = a * e - b * b;
            s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0) {
                t = 0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1) {
                t = 1;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    return length((p0 + d1 * s) - (q0 + d2 * t));
}

// A scratch's centre line on the face (profile point (0, 0) along its path), as a polyline of
// n + 1 points, n = path length / (a tenth of a camera pixel) clamped to [8, 512].
std::vector<Vec3> scratch_centre_line(const Scene& scene, const Defect& d, double pitch) {
    const ScratchPath path = scratch_path(Lens(scene.object.lens), d);
    const int n = static_cast<int>(std::clamp(std::ceil(path.path_length() / (0.1 * pitch)), 8.0, 512.0));
    std::vector<Vec3> line;
    for (int i = 0; i <= n; ++i) line.push_back(path.place(static_cast<double>(i) / n, Point2{0.0, 0.0}));
    return line;
}

// The smallest distance between a principal path's polyline and another polyline.
double min_distance_along(const PrincipalPath& p, const Vec3& start, const std::vector<Vec3>& line) {
    Vec3 prev = start;
    double m = INFINITY;
    for (size_t i = 0; i <= p.vertices.size(); ++i) {
        const Vec3 next = i < p.vertices.size() ? p.vertices[i] : prev + p.direction * 1e3;
        for (size_t j = 0; j + 1 < line.size(); ++j) m = std::min(m, segment_distance(prev, next, line[j], line[j + 1]));
        prev = next;
    }
    return m;
}

bool in_aperture(const Scene& s, const Vec3& c) { return std::hypot(c.x, c.y) <= 0.95 * 0.5 * s.object.lens.diameter; }

// The geometric surround shell of defect d (see Experiment.h).
Region surround_shell(const Tracer& free, const Scene& scene, const Defect& d) {
    const double pitch = scene.camera.size[0] / scene.camera.resolution[0];
    const bool scratch = d.type == DefectType::Scratch;
    const double r = scratch ? std::min(0.5 * d.width, d.depth) : std::min({d.semi_axes.x, d.semi_axes.y, d.semi_axes.z});
    const double inner = 2 * r + 2 * pitch, outer = 5 * r + 4 * pitch;
    // A scratch's cross-section lies within its width x depth box below the centre line, so
    // within hypot(w / 2, depth) of it: the tube the shell lies beyond.
    const double tube = scratch ? std::hypot(0.5 * d.width, d.depth) : 0.0;
    const std::vector<Vec3> line = scratch ? scratch_centre_line(scene, d, pitch) : std::vector<Vec3>{};
    Region reg;
    for (long k = 0; k < free.camera().pixels(); ++k) {
        const Vec3 c = free.camera().pixel_centre(k);
        if (!in_aperture(scene, c)) continue;
        const Vec3 start{c.x, c.y, -1e3};
        const PrincipalPath p = free.principal_path(start, {0, 0, 1});
        bool in_shell;
        if (scratch) {
            // Beyond the tube around the centre line by inner .. outer.
            const double dist = min_distance_along(p, start, line);
            in_shell = dist <= tube + outer && dist > tube + inner;
        } else {
            in_shell = min_rho2_along(p, start, d, outer) <= 1.0 && min_rho2_along(p, start, d, inner) > 1.0;
        }
        if (in_shell) reg.pixels.push_back(static_cast<int>(k));
    }
    return reg;
}

// The size that ranks defects (the smallest are the paper's claim): the largest semi-axis of an
// ellipsoid, the half-width of a scratch.
double ranking_size(const Defect& d) { return d.type == DefectType::Scratch ? 0.5 * d.width : d.max_semi_axis(); }

}  // namespace

const std::vector<std::string>& defect_size_columns() {
    static const std::vector<std::string> columns = {"semi_axis_a_mm", "semi_axis_b_mm", "semi_axis_c_mm",
                                                     "width_mm",       "depth_mm",       "length_mm"};
    return columns;
}

std::vector<std::pair<std::string, double>> defect_size(const Scene& scene, const Defect& d) {
    if (d.type == DefectType::Scratch)
        return {{"width_mm", d.width},
                {"depth_mm", d.depth},
                {"length_mm", scratch_path(Lens(scene.object.lens), d).path_length()}};
    return {{"semi_axis_a_mm", d.semi_axes.x}, {"semi_axis_b_mm", d.semi_axes.y}, {"semi_axis_c_mm", d.semi_axes.z}};
}

std::string DefectRegions::describe() const {
    auto at = [&](const std::string& key) {
        for (const auto& [k, v] : size)
            if (k == key) return v;
        return static_cast<double>(NAN);
    };
    if (kind == "scratch")
        return fmt::format("scratch {:.3g} x {:.3g} mm, {:.3g} mm long", at("width_mm"), at("depth_mm"), at("length_mm"));
    const double a = at("semi_axis_a_mm"), b = at("semi_axis_b_mm"), c = at("semi_axis_c_mm");
    if (a == b && b == c) return fmt::format("{} r = {:.4g} mm", kind, a);
    return fmt::format("{} {:.3g} x {:.3g} x {:.3g} mm", kind, a, b, c);
}

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
        g.kind = to_string(d.type);
        g.size = defect_size(scene, d);
        g.defect_pixels = traced_defect_region(scene, r.run.render, static_cast<int>(k), spec.defect_fraction);
        auto& px = g.defect_pixels.pixels;
        px.erase(std::remove_if(px.begin(), px.end(), [&](int p) { return !in_aperture(scene, free.camera().pixel_centre(p)); }),
                 px.end());
        g.surround = subtract(surround_shell(free, scene, d), met);
        out.push_back(std::move(g));
    }
    return out;
}

io::Json DefectRegions::size_json() const {
    io::Json j = io::Json::object();
    for (const auto& [k, v] : size) j[k] = v;
    return j;
}

io::Json regions_json(const std::vector<DefectRegions>& regions) {
    io::Json defects = io::Json::array();
    for (const DefectRegions& g : regions) {
        defects.push_back({{"defect", g.defect}, {"kind", g.kind}, {"size", g.size_json()}, {"defect_pixels", g.defect_pixels.pixels},
                           {"surround_pixels", g.surround.pixels}});
    }
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
        for (const char* key : {"defect", "kind", "size", "defect_pixels", "surround_pixels"})
            if (!d.contains(key)) fail(fmt::format("{}: missing key '{}'", at, key));
        if (!d["defect"].is_number_integer()) fail(at + ".defect: expected an integer");
        if (!d["kind"].is_string()) fail(at + ".kind: expected a defect kind");
        if (!d["size"].is_object()) fail(at + ".size: expected an object of sizes in mm");
        g.defect = d["defect"].get<int>();
        g.kind = d["kind"].get<std::string>();
        for (const auto& [k, v] : d["size"].items()) {
            if (!v.is_number()) fail(fmt::format("{}.size.{}: expected a number (mm)", at, k));
            g.size.emplace_back(k, v.get<double>());
        }
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

Resolution rendered_resolution(int samples_per_pixel, const DisplayGrid& display) {
    // One sample of S carries 1 / S of a pixel's light, and moving it by one display pixel moves
    // the pixel's energy-weighted moments (mean position, ellipse widths) by 1 / S of a pitch.
    const double S = samples_per_pixel;
    Resolution q;
    q.fraction = 1.0 / S;
    q.mm = std::min(display.width / display.Q, display.height / display.P) / S;
    q.moment = 1.0 / S;
    return q;
}

Resolution rendered_resolution(const Scene& scene) {
    return rendered_resolution(scene.camera.samples_per_pixel, display_grid(scene));
}

ContrastResult measure_cnr(const std::vector<float>& image, const DefectRegions& g, double resolution) {
    ContrastResult c;
    c.defect_mean = c.surround_mean = c.surround_std = c.noise = NAN;  // not measured
    if (g.defect_pixels.pixels.empty()) {
        c.cnr = 0;  // not imaged: no contrast
        return c;
    }
    int nd = 0, ns = 0;
    for (int k : g.defect_pixels.pixels) nd += std::isfinite(image[static_cast<std::size_t>(k)]) ? 1 : 0;
    for (int k : g.surround.pixels) ns += std::isfinite(image[static_cast<std::size_t>(k)]) ? 1 : 0;
    if (nd < 1 || ns < 2) {
        c.cnr = NAN;
        return c;
    }
    return contrast_to_noise(image, g.defect_pixels, g.surround, resolution);
}

namespace {

// The valid pixels of the false-positive count: within 0.95 of the clear aperture.
Region aperture_pixels(const Scene& s) {
    Region valid;
    const TelecentricCamera camera(s.camera, 0.0);
    for (long k = 0; k < camera.pixels(); ++k)
        if (in_aperture(s, camera.pixel_centre(k))) valid.pixels.push_back(static_cast<int>(k));
    return valid;
}

// A CNR for the tables: '-' for none (NaN, or weakest_of's -1 for one that could not be measured).
std::string cnr_text(double c) { return std::isnan(c) || c < 0 ? std::string("-") : fmt::format("{:.3g}", c); }

// The numbers of one image kind (rendered or measured) over every scene and defect.
struct ImageNumbers {
    std::map<std::string, std::vector<double>> cnr;            // channel -> per defect column
    std::map<std::string, std::vector<double>> smallest_cnr;   // channel -> CNRs of the smallest defects
    std::map<std::string, int> false_pos;                      // channel -> in the reference scene
};

// The weakest CNR of a list (one that could not be measured, NaN, counts as -1), NaN if empty.
double weakest_of(const std::vector<double>& v) {
    double w = INFINITY;
    for (double c : v) w = std::min(w, std::isnan(c) ? -1.0 : c);
    return v.empty() ? NAN : w;
}

// The best candidate (see Experiment.h): among those whose weakest CNR over the smallest defects
// reaches kVisibleCnr, the fewest false positives, then the largest weakest CNR; if none reaches
// it, the largest weakest CNR. "" if no candidate has numbers.
std::string best_candidate(const std::vector<std::string>& candidates, const ImageNumbers& n, double* weakest_out) {
    std::string best;
    bool best_visible = false;
    int best_fp = INT32_MAX;
    double best_cnr = -INFINITY;
    for (const auto& ch : candidates) {
        const auto it = n.smallest_cnr.find(ch);
        if (it == n.smallest_cnr.end() || std::none_of(it->second.begin(), it->second.end(), [](double c) { return !std::isnan(c); }))
            continue;  // no CNR measured on the smallest defects
        const auto fp_it = n.false_pos.find(ch);
        const int fp = fp_it == n.false_pos.end() ? INT32_MAX - 1 : fp_it->second;
        const double weakest = weakest_of(it->second);
        const bool visible = weakest >= kVisibleCnr;
        const bool better = best.empty() || (visible && !best_visible) ||
                            (visible == best_visible &&
                             (visible ? (fp < best_fp || (fp == best_fp && weakest > best_cnr)) : weakest > best_cnr));
        if (better) {
            best = ch;
            best_visible = visible;
            best_fp = fp;
            best_cnr = weakest;
        }
    }
    if (weakest_out) *weakest_out = best_cnr;
    return best;
}

// The montage's marks: a ring around each defect's traced pixels, in data pixels (Contrast.h's
// coordinates), through their centroid and a pixel and a half beyond the farthest of them.
std::vector<Ring> defect_rings(const std::vector<DefectRegions>& regions, int width) {
    std::vector<Ring> rings;
    for (const DefectRegions& g : regions) {
        if (g.defect_pixels.pixels.empty()) continue;
        double cx = 0, cy = 0;
        for (int k : g.defect_pixels.pixels) {
            cx += k % width + 0.5;
            cy += k / width + 0.5;
        }
        cx /= static_cast<double>(g.defect_pixels.pixels.size());
        cy /= static_cast<double>(g.defect_pixels.pixels.size());
        double r = 0;
        for (int k : g.defect_pixels.pixels) r = std::max(r, std::hypot(k % width + 0.5 - cx, k / width + 0.5 - cy));
        rings.push_back({cx, cy, r + 1.5});
    }
    return rings;
}

}  // namespace

ExperimentResult evaluate_experiment(const ExperimentSpec& spec, const std::vector<ExperimentScene>& runs,
                                     const Measurement* measured) {
    if (measured && measured->scenes.size() != runs.size())
        throw std::invalid_argument("evaluate_experiment: one measurement per scene is needed");
    ExperimentResult out;
    std::vector<std::string> channels;
    for (const auto& r : runs)
        for (const auto& [name, v] : r.run.features.channels)
            if (std::find(channels.begin(), channels.end(), name) == channels.end()) channels.push_back(name);
    double smallest = INFINITY;
    for (const auto& r : runs)
        for (const auto& d : r.scene.defects) smallest = std::min(smallest, ranking_size(d));

    std::string csv = "scene,defect,kind";
    for (const auto& c : defect_size_columns()) csv += "," + c;
    csv += ",channel,defect_pixels,surround_pixels,defect_mean,surround_mean,surround_std,noise,cnr";
    if (measured) csv += ",measured_by,measured_defect_mean,measured_surround_mean,measured_surround_std,measured_noise,measured_cnr";
    csv += "\n";
    std::vector<std::string> md_columns;
    ImageNumbers rendered, meas;
    for (std::size_t si = 0; si < runs.size(); ++si) {
        const ExperimentScene& r = runs[si];
        const MeasuredImages* m = measured ? &measured->scenes[si] : nullptr;
        const Resolution q = rendered_resolution(r.scene);
        out.regions.push_back(experiment_regions(spec, r));
        for (const DefectRegions& g : out.regions.back()) {
            const int k = g.defect;
            const bool small = ranking_size(r.scene.defects[static_cast<std::size_t>(k)]) == smallest;
            md_columns.push_back(fmt::format("{} #{}", r.label, k));
            for (const auto& ch : channels) {
                if (!r.run.features.has(ch)) continue;
                const ContrastResult c = measure_cnr(r.run.features.channel(ch), g, q.of(ch));
                std::string line = fmt::format("{},{},{}", r.stem, k, g.kind);
                for (const auto& col : defect_size_columns()) {
                    std::string v;
                    for (const auto& [key, value] : g.size)
                        if (key == col) v = fmt::format("{}", value);
                    line += "," + v;
                }
                line += fmt::format(",{},{},{},{},{},{},{},{}", ch, c.defect_pixels, c.surround_pixels, c.defect_mean,
                                    c.surround_mean, c.surround_std, c.noise, c.cnr);
                rendered.cnr[ch].push_back(c.cnr);
                if (small) rendered.smallest_cnr[ch].push_back(c.cnr);
                if (measured) {
                    ContrastResult mc;
                    mc.cnr = NAN;
                    std::string how;
                    if (m->features.has(ch)) {
                        mc = measure_cnr(m->features.channel(ch), g, m->resolution.at(ch));
                        how = m->how.at(ch);
                    }
                    line += fmt::format(",{},{},{},{},{},{}", how, mc.defect_mean, mc.surround_mean, mc.surround_std,
                                        mc.noise, mc.cnr);
                    meas.cnr[ch].push_back(mc.cnr);
                    if (small && m->features.has(ch)) meas.smallest_cnr[ch].push_back(mc.cnr);
                }
                csv += line + "\n";
            }
        }
    }
    // False positives of the reference scene, within 0.95 of the clear aperture.
    std::string fp_csv = "scene,channel,false_positives";
    if (measured) fp_csv += ",measured_false_positives";
    fp_csv += "\n";
    for (std::size_t si = 0; si < runs.size(); ++si) {
        const ExperimentScene& r = runs[si];
        if (r.file != spec.reference) continue;
        const Region valid = aperture_pixels(r.scene);
        for (const auto& ch : channels) {
            if (!r.run.features.has(ch)) continue;
            rendered.false_pos[ch] = false_positives(r.run.features.channel(ch), valid);
            fp_csv += fmt::format("{},{},{}", r.stem, ch, rendered.false_pos[ch]);
            if (measured) {
                const MeasuredImages& m = measured->scenes[si];
                if (m.features.has(ch)) {
                    meas.false_pos[ch] = false_positives(m.features.channel(ch), valid);
                    fp_csv += fmt::format(",{}", meas.false_pos[ch]);
                } else {
                    fp_csv += ",";
                }
            }
            fp_csv += "\n";
        }
    }
    out.csv = std::move(csv);
    out.false_positives_csv = std::move(fp_csv);

    // The best new feature, on the measured images when there are any.
    const ImageNumbers& judged = measured ? meas : rendered;
    double weakest = NAN;
    out.best = best_candidate(spec.candidates, judged, &weakest);
    const std::string where = measured ? "measured under the sensor model" : "in the rendered images";
    if (spec.candidates.empty()) {
        out.headline = "No new feature is judged: experiment.yaml lists no candidates.";
    } else if (out.best.empty()) {
        out.headline = "No candidate has a CNR on the smallest defects.";
    } else {
        const auto bf = judged.smallest_cnr.find("BrightField");
        const auto fp = judged.false_pos.find(out.best);
        const int fps = fp == judged.false_pos.end() ? -1 : fp->second;
        out.headline = fmt::format(
            "Best new feature {}: **{}**{}: weakest CNR {} on the smallest defects against the bright field's {}; {} in "
            "the defect-free scene.",
            where, out.best,
            measured && measured->scenes.front().how.count(out.best)
                ? ", by " + measured->scenes.front().how.at(out.best)
                : std::string(),
            cnr_text(weakest), bf == judged.smallest_cnr.end() ? std::string("-") : cnr_text(weakest_of(bf->second)),
            fps < 0 ? std::string("no count of false positives") : fmt::format("{} false positive{}", fps, fps == 1 ? "" : "s"));
    }

    std::string md = "# Contrast-to-noise ratio of every defect in every image\n\n" + out.headline + "\n\n";
    md += fmt::format(
        "CNR = |mean(defect) - mean(surround)| / noise, the noise the surround's standard deviation but never less than "
        "the image's resolution q / sqrt 12 (docs/features.md). Defect: the pixels at least {:g} of whose paths meet the "
        "defect first (traced); surround: the shell 2r + 2 px .. 5r + 4 px beyond the defect (its ellipsoid, r its "
        "smallest semi-axis; a scratch's tube of radius hypot(w / 2, depth), r the smaller of w / 2 and depth) along the "
        "defect-free object's "
        "centre rays, minus every pixel a path of which met a defect; both within 0.95 of the clear aperture. False "
        "positives: defect-free pixels within 0.95 of the aperture more than 5 x 1.4826 MAD from the median. Best new "
        "feature: among the candidates whose weakest CNR over the smallest defects is at least 5 (the Rose criterion), "
        "the fewest false positives, then the largest weakest CNR; if none reaches 5, the largest weakest CNR. A '-' is a defect whose image has no finite pixel (or a surround with fewer than 2); a defect with "
        "no traced pixel within 0.95 of the aperture has no image and CNR 0.\n\n",
        spec.defect_fraction);
    auto table = [&](const std::string& title, const ImageNumbers& n, const MeasuredImages* how) {
        md += "## " + title + "\n\n| image |" + (how ? std::string(" measured by |") : std::string());
        for (const auto& c : md_columns) md += " " + c + " |";
        md += " false positives (defect-free) |\n|---|";
        for (size_t i = 0; i <= md_columns.size() + (how ? 1 : 0); ++i) md += "---|";
        md += "\n";
        for (const auto& ch : channels) {
            const auto it = n.cnr.find(ch);
            if (it == n.cnr.end() || it->second.empty()) continue;
            if (how && !how->how.count(ch)) continue;
            md += "| " + ch + " |" + (how ? " " + how->how.at(ch) + " |" : std::string());
            for (double c : it->second) md += " " + cnr_text(c) + " |";
            const auto fp = n.false_pos.find(ch);
            md += fmt::format(" {} |\n", fp == n.false_pos.end() ? std::string("-") : std::to_string(fp->second));
        }
        md += "\n";
    };
    if (measured)
        table("Measured: the images an instrument would take (" + measured->instrument + ")", meas,
              &measured->scenes.front());
    table("Rendered: the images of T itself (Monte Carlo noise; the deflection map against an independently rendered "
          "reference)",
          rendered, nullptr);
    out.markdown = std::move(md);

    // The montage: rows are images, columns are scenes; one colour scale per row (the range of the
    // row's finite values over every scene), each defect ringed. The best new feature follows the
    // montage's rows as rendered and, when it was judged on them, as measured.
    struct Row {
        std::string channel;
        bool measured = false;
    };
    std::vector<Row> rows;
    for (const auto& ch : spec.montage) rows.push_back({ch, false});
    if (!out.best.empty() && std::find(spec.montage.begin(), spec.montage.end(), out.best) == spec.montage.end())
        rows.push_back({out.best, false});
    if (!out.best.empty() && measured) rows.push_back({out.best, true});
    auto image_of = [&](std::size_t si, const Row& row) -> const FeatureImages& {
        return row.measured ? measured->scenes[si].features : runs[si].run.features;
    };
    std::vector<std::vector<Image>> cells;
    std::vector<std::string> col_labels;
    for (const auto& r : runs) col_labels.push_back(r.label);
    std::vector<std::string> row_labels;
    for (const Row& row : rows) {
        std::vector<float> all;
        for (std::size_t si = 0; si < runs.size(); ++si)
            if (image_of(si, row).has(row.channel)) {
                const auto& v = image_of(si, row).channel(row.channel);
                all.insert(all.end(), v.begin(), v.end());
            }
        const auto [lo, hi] = colour_range(all, NAN, NAN);
        std::vector<Image> cells_of_row;
        for (std::size_t si = 0; si < runs.size(); ++si) {
            const FeatureImages& f = image_of(si, row);
            if (!f.has(row.channel)) {
                cells_of_row.emplace_back();
                continue;
            }
            const Scene& sc = runs[si].scene;
            cells_of_row.push_back(pseudo_colour(f.channel(row.channel), f.width, f.height, "", lo, hi,
                                                 std::max(1, 300 / f.width), {sc.camera.size[0], sc.camera.size[1]},
                                                 defect_rings(out.regions[si], f.width)));
        }
        cells.push_back(std::move(cells_of_row));
        row_labels.push_back(feature_title(row.channel) + (row.measured ? ", measured" : ""));
    }
    out.montage = montage(cells, row_labels, col_labels,
                          "Simulated inspection images (columns: scenes; rows: images, one colour scale each; rings: defects)");
    return out;
}

}  // namespace ltm
