#include "app/FeatureOutputs.h"

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "app/JsonLine.h"
#include "io/Image.h"
#include "features/Plot.h"
#include "io/AtomicFile.h"
#include "app/Commands.h"
#include "scene/SceneJson.h"
#include "io/LtmFile.h"

namespace ltm::app {

namespace fs = std::filesystem;

namespace {

const JsonValue& member(const JsonValue& v, const std::string& key, const std::string& file) {
    if (v.type == JsonValue::Type::Object)
        for (const auto& [k, x] : v.object)
            if (k == key) return x;
    throw std::runtime_error(fmt::format("{}: missing \"{}\"", file, key));
}

double number_at(const JsonValue& v, size_t i, const std::string& file, const std::string& what) {
    if (v.type != JsonValue::Type::Array || v.array.size() <= i || v.array[i].type != JsonValue::Type::Number)
        throw std::runtime_error(fmt::format("{}: \"{}\" is not a list of numbers", file, what));
    return v.array[i].number;
}

}  // namespace

namespace {

std::string stats_json(const PathStats& s) {
    return fmt::format(
        "{{\"paths\": {}, \"segments\": {}, \"segments_per_path\": {}, \"reflections\": {}, \"transmissions\": {}, "
        "\"total_internal_reflections\": {}, \"absorbed_by_particles\": {}, \"absorbed_by_rim\": {}, "
        "\"on_display\": {}, \"off_display\": {}, \"toward_camera\": {}, \"roulette_kills\": {}, \"truncated\": {}, "
        "\"nan_events\": {}, \"spurious_candidates\": {}, \"guard_hits\": {}, \"leak_retries\": {}, "
        "\"leaks_unresolved\": {}, \"grin_segments\": {}, \"grin_evaluations\": {}, \"tet_crossings\": {}, "
        "\"lost\": {}, \"hamiltonian_violations\": {}, \"walk_boundary_exits\": {}, "
        "\"display_weight\": {}, \"lost_weight\": {}, \"absorbed_weight\": {}}}",
        s.paths, s.segments, json_number(s.paths ? double(s.segments) / double(s.paths) : 0.0), s.reflections,
        s.transmissions, s.tir, s.absorbed_particle, s.absorbed_rim, s.on_display, s.off_display, s.toward_camera,
        s.roulette_kills, s.truncated, s.nan_events, s.spurious_candidates, s.guard_hits, s.leak_retries,
        s.leaks_unresolved, s.grin_segments, s.grin_evaluations, s.tet_crossings, s.lost, s.hamiltonian_violations,
        s.walk_boundary_exits, json_number(s.display_weight), json_number(s.lost_weight), json_number(s.absorbed_weight));
}

}  // namespace

void write_run_json(const std::string& dir, const Scene& scene, const RenderResult& r, Representation representation,
                    int threads, const std::string& result, const StageReport& report) {
    const std::string run_json = fmt::format(
        "{{\n  \"ltmsim_version\": \"{}\",\n  \"scene\": {},\n  \"seed\": {},\n  \"representation\": \"{}\",\n"
        "  \"threads\": {},\n  \"result\": {},\n  \"render_seconds\": {},\n  \"stages\": {},\n  \"path_statistics\": {}\n}}\n",
        kVersion, scene_to_json(scene, 2), scene.seed, to_string(representation), threads, result, json_number(r.seconds),
        report.to_json(), stats_json(r.stats));
    io::write_file((fs::path(dir) / "run.json").string(), run_json, "run record");
}

void write_render_folder(const std::string& dir, const Scene& scene, const SceneRun& run, int threads,
                         StageReport& report) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    const fs::path d(dir);
    std::vector<fs::path> written;
    const RenderResult& r = run.render;
    try {
        StageTimer t_write(&report, "write");
        write_ltm_npz((d / "ltm.npz").string(), r.T);
        written.push_back(d / "ltm.npz");
        if (!scene.defects.empty()) {
            std::vector<float> mx(run.reference.size() / 2), my(run.reference.size() / 2);
            for (size_t k = 0; k < mx.size(); ++k) {
                mx[k] = run.reference[2 * k];
                my[k] = run.reference[2 * k + 1];
            }
            write_exr((d / "reference.exr").string(), scene.camera.resolution[0], scene.camera.resolution[1],
                      {{"MeanX", mx}, {"MeanY", my}});
            written.push_back(d / "reference.exr");
        }
        written.push_back(d / "features.exr");
        written.push_back(d / "features.npz");
        write_feature_images(dir, run.features, {scene.camera.size[0], scene.camera.size[1]});
        t_write.done(dir);
        write_run_json(dir, scene, r, run.representation, threads,
                       fmt::format("{{\"rows\": {}, \"cols\": {}, \"nnz\": {}, \"reference_pixels\": {}}}", r.T.rows,
                                   r.T.cols, r.T.nnz(), run.reference_pixels),
                       report);
    } catch (...) {
        for (const auto& p : written) fs::remove(p, ec);
        throw;
    }
}

RenderGeometry render_geometry(const Scene& s) {
    return {s.camera.resolution[0], s.camera.resolution[1],
            {s.display.resolution[0], s.display.resolution[1], s.display.size[0], s.display.size[1]}};
}

RenderGeometry read_render_geometry(const std::string& dir) {
    const std::string file = (fs::path(dir) / "run.json").string();
    std::ifstream in(file);
    if (!in) throw std::runtime_error(fmt::format("{}: cannot read (it holds the camera and display of the render)", file));
    std::stringstream ss;
    ss << in.rdbuf();
    JsonValue root;
    try {
        root = parse_json_line(ss.str());
    } catch (const JsonError& e) {
        throw std::runtime_error(fmt::format("{}: malformed JSON ({})", file, e.what()));
    }
    const JsonValue& scene = member(root, "scene", file);
    const JsonValue& cam = member(scene, "camera", file);
    const JsonValue& disp = member(scene, "display", file);
    RenderGeometry g;
    g.camera_columns = static_cast<int>(number_at(member(cam, "resolution", file), 0, file, "camera.resolution"));
    g.camera_rows = static_cast<int>(number_at(member(cam, "resolution", file), 1, file, "camera.resolution"));
    g.display.Q = static_cast<int>(number_at(member(disp, "resolution", file), 0, file, "display.resolution"));
    g.display.P = static_cast<int>(number_at(member(disp, "resolution", file), 1, file, "display.resolution"));
    g.display.width = number_at(member(disp, "size", file), 0, file, "display.size");
    g.display.height = number_at(member(disp, "size", file), 1, file, "display.size");
    return g;
}

std::optional<std::vector<float>> read_reference(const std::string& dir, int camera_pixels) {
    const fs::path file = fs::path(dir) / "reference.exr";
    if (!fs::exists(file)) return std::nullopt;
    int w = 0, h = 0;
    const auto channels = read_exr_channels(file.string(), &w, &h);
    const std::vector<float>* mx = nullptr;
    const std::vector<float>* my = nullptr;
    for (const auto& [name, values] : channels) {
        if (name == "MeanX") mx = &values;
        if (name == "MeanY") my = &values;
    }
    if (!mx || !my || w * h != camera_pixels)
        throw std::runtime_error(fmt::format("{}: expected channels MeanX and MeanY of {} pixels", file.string(), camera_pixels));
    std::vector<float> ref(2 * static_cast<size_t>(camera_pixels));
    for (int k = 0; k < camera_pixels; ++k) {
        ref[2 * static_cast<size_t>(k)] = (*mx)[static_cast<size_t>(k)];
        ref[2 * static_cast<size_t>(k) + 1] = (*my)[static_cast<size_t>(k)];
    }
    return ref;
}

FeatureImages write_features(const std::string& dir, const CsrMatrix& T, const RenderGeometry& g,
                             const FeatureOptions& options, const std::vector<float>* reference,
                             const ImageExtent& camera) {
    FeatureOptions o = options;
    if (o.dark_block < 0) o.dark_block = std::min({60, g.display.P, g.display.Q});  // automatic
    const FeatureImages f = compute_features(T, g.camera_columns, g.camera_rows, g.display, o, reference);
    write_feature_images(dir, f, camera);
    return f;
}

void write_feature_images(const std::string& dir, const FeatureImages& f, const ImageExtent& camera) {
    write_exr((fs::path(dir) / "features.exr").string(), f.width, f.height, f.channels);
    write_npz_channels((fs::path(dir) / "features.npz").string(), f.width, f.height, f.channels);
    const fs::path pngs = fs::path(dir) / "features";
    fs::create_directories(pngs);
    // Pseudo colour, scaled so a 100-pixel-wide image is ~400 pixels wide.
    const int scale = std::max(1, 400 / std::max(1, f.width));
    for (const auto& [name, values] : f.channels)
        write_pseudo_colour_png((pngs / (name + ".png")).string(), values, f.width, f.height, feature_title(name), NAN,
                                NAN, scale, camera);
}

}  // namespace ltm::app
