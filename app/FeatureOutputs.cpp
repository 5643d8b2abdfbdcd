#include "app/FeatureOutputs.h"

#include <sys/resource.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <stdexcept>

#include "io/AtomicFile.h"
#include "io/Image.h"
#include "features/Plot.h"
#include "io/Json.h"
#include "app/Commands.h"
#include "scene/SceneJson.h"
#include "io/LtmFile.h"

namespace ltm::app {

namespace fs = std::filesystem;

namespace {

io::Json stats_json(const PathStats& s) {
    return {{"paths", s.paths},
            {"segments", s.segments},
            {"segments_per_path", io::json_number(s.paths ? double(s.segments) / double(s.paths) : 0.0)},
            {"reflections", s.reflections},
            {"transmissions", s.transmissions},
            {"total_internal_reflections", s.tir},
            {"absorbed_by_particles", s.absorbed_particle},
            {"absorbed_by_rim", s.absorbed_rim},
            {"on_display", s.on_display},
            {"off_display", s.off_display},
            {"toward_camera", s.toward_camera},
            {"roulette_kills", s.roulette_kills},
            {"splits", s.splits},
            {"branches", s.branches},
            {"truncated", s.truncated},
            {"nan_events", s.nan_events},
            {"spurious_candidates", s.spurious_candidates},
            {"guard_hits", s.guard_hits},
            {"leak_retries", s.leak_retries},
            {"leaks_unresolved", s.leaks_unresolved},
            {"seam_repairs", s.seam_repairs},
            {"edge_chords", s.edge_chords},
            {"packet_segments", s.packet_segments},
            {"packet_fallbacks", s.packet_fallbacks},
            {"grin_segments", s.grin_segments},
            {"grin_evaluations", s.grin_evaluations},
            {"tet_crossings", s.tet_crossings},
            {"lost", s.lost},
            {"hamiltonian_violations", s.hamiltonian_violations},
            {"walk_boundary_exits", s.walk_boundary_exits},
            {"display_weight", io::json_number(s.display_weight)},
            {"lost_weight", io::json_number(s.lost_weight)},
            {"absorbed_weight", io::json_number(s.absorbed_weight)}};
}

// The value at `path` (keys from the root) of run.json, which must be a list of at least n
// numbers; std::runtime_error naming the file and the key otherwise.
std::vector<double> numbers_at(const io::Json& root, const std::vector<std::string>& path, std::size_t n,
                               const std::string& file) {
    std::string key;
    const io::Json* v = &root;
    for (const std::string& k : path) {
        key += (key.empty() ? "" : ".") + k;
        if (!v->is_object() || !v->contains(k)) throw std::runtime_error(fmt::format("{}: missing \"{}\"", file, key));
        v = &(*v)[k];
    }
    std::vector<double> out;
    if (v->is_array())
        for (const io::Json& x : *v)
            if (x.is_number()) out.push_back(x.get<double>());
    if (!v->is_array() || out.size() != v->size() || out.size() < n)
        throw std::runtime_error(fmt::format("{}: \"{}\" is not a list of {} numbers", file, key, n));
    return out;
}

}  // namespace

void write_run_json(const std::string& dir, const Scene& scene, const RenderResult& r, Representation representation,
                    int threads, const io::Json& result, const StageReport& report, const io::Json& memory) {
    io::Json run = {{"ltmsim_version", kVersion},
                          {"scene", scene_to_json(scene)},
                          {"seed", scene.seed},
                          {"representation", to_string(representation)},
                          {"estimator", tracing_to_json(scene.tracing)},
                          {"threads", threads},
                          {"result", result},
                          {"render_seconds", io::json_number(r.seconds)},
                          {"stages", report.to_json()},
                          {"path_statistics", stats_json(r.stats)}};
    if (!memory.is_null()) {
        io::Json m = memory;
        rusage ru{};
        getrusage(RUSAGE_SELF, &ru);
        m["process_peak_rss_bytes"] = static_cast<std::uint64_t>(ru.ru_maxrss) * 1024;  // kB on Linux
        run["memory"] = std::move(m);
    }
    io::write_json_file((fs::path(dir) / "run.json").string(), run, "run record");
}

io::Json memory_json(const RenderMemory& m, const RenderResult& r, std::int64_t rows, std::size_t max_matrix_bytes) {
    io::Json j = io::Json::object();
    if (m.measured) {
        j["render_peak_rss_bytes"] = m.peak_rss_bytes;
        j["render_start_rss_bytes"] = m.start_rss_bytes;
        j["render_peak_is_per_run"] = m.per_run;
        j["peak_rss_method"] = m.method;
    }
    // What T's arrays take in memory: int32 indices and float32 data per nonzero, int64 indptr.
    if (rows > 0) j["matrix_bytes"] = 8 * static_cast<std::uint64_t>(r.nnz) + 8 * (static_cast<std::uint64_t>(rows) + 1);
    j["max_memory_bytes"] = static_cast<std::uint64_t>(max_matrix_bytes);
    j["streamed"] = r.streamed;
    return j;
}

void write_render_folder(const std::string& dir, const Scene& scene, const SceneRun& run, int threads,
                         StageReport& report, const io::Json& memory, bool previews) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    const fs::path d(dir);
    std::vector<fs::path> written;
    const RenderResult& r = run.render;
    const std::int64_t rows = static_cast<std::int64_t>(scene.camera.resolution[0]) * scene.camera.resolution[1];
    const std::int64_t cols = static_cast<std::int64_t>(scene.display.resolution[0]) * scene.display.resolution[1];
    try {
        StageTimer t_write(&report, "write");
        // The matrix, the reference and the feature images are independent files: written in
        // parallel, each atomically, and made durable together (io::CommitGroup: one fsync of
        // each folder and a journal commit shared by the files, instead of two fsyncs a file).
        // A failure before the group's commit leaves every path as it was; after, the files
        // in place are removed.
        io::CommitGroup group;
        io::NpzWriteOptions npz;
        npz.group = &group;
        tbb::parallel_invoke(
            [&] {
                if (r.streamed)
                    run.streamed_T->commit(&group);  // the archive from the spilled rows
                else
                    write_ltm_npz((d / "ltm.npz").string(), r.T, npz);
            },
            [&] {
                // The interleaved x, y means, read in place (copies of them page-faulted 16 MB
                // fresh at industrial scale, about 40 ms).
                const std::size_t pixels = run.reference.size() / 2;
                const float* const xy = pixels > 0 ? run.reference.data() : nullptr;  // write_exr refuses 0 pixels
                write_exr((d / "reference.exr").string(), scene.camera.resolution[0], scene.camera.resolution[1],
                          {{"MeanX", xy, pixels, 2}, {"MeanY", xy ? xy + 1 : nullptr, pixels, 2}}, &group);
            },
            [&] {
                write_feature_images(dir, run.features, {scene.camera.size[0], scene.camera.size[1]}, previews,
                                     &group);
            });
        for (const char* f : render_folder_files())
            if (std::string(f) != "run.json") written.push_back(d / f);
        group.commit();
        t_write.done(dir);
        write_run_json(dir, scene, r, run.representation, threads,
                       {{"rows", rows}, {"cols", cols}, {"nnz", r.nnz}, {"streamed", r.streamed}, {"reference_pixels", run.reference_pixels}, {"reference_reused", run.reference_reused}, {"previews", previews}},
                       report, memory);
    } catch (...) {
        for (const auto& p : written) fs::remove(p, ec);
        throw;
    }
}

std::vector<const char*> render_folder_files() {
    return {"ltm.npz", "features.exr", "features.npz", "reference.exr", "run.json"};
}

RenderGeometry render_geometry(const Scene& s) {
    return {s.camera.resolution[0], s.camera.resolution[1], {s.camera.size[0], s.camera.size[1]},
            {s.display.resolution[0], s.display.resolution[1], s.display.size[0], s.display.size[1]},
            s.camera.samples_per_pixel};
}

RenderGeometry read_render_geometry(const std::string& dir) {
    const std::string file = (fs::path(dir) / "run.json").string();
    if (!fs::exists(file))
        throw std::runtime_error(fmt::format("{}: cannot read (it holds the camera and display of the render)", file));
    const io::Json root = io::read_json_file(file, "run record");
    const auto camera = numbers_at(root, {"scene", "camera", "resolution"}, 2, file);
    const auto display = numbers_at(root, {"scene", "display", "resolution"}, 2, file);
    const auto size = numbers_at(root, {"scene", "display", "size"}, 2, file);
    RenderGeometry g;
    g.camera_columns = static_cast<int>(camera[0]);
    g.camera_rows = static_cast<int>(camera[1]);
    g.display.Q = static_cast<int>(display[0]);
    g.display.P = static_cast<int>(display[1]);
    g.display.width = size[0];
    g.display.height = size[1];
    // The samples per pixel give the rendered images' resolution (acquire's exact CNRs).
    const io::Json& camera_json = root["scene"]["camera"];
    if (camera_json.contains("samples_per_pixel") && camera_json["samples_per_pixel"].is_number_integer())
        g.samples_per_pixel = camera_json["samples_per_pixel"].get<int>();
    // The camera's field of view only labels the previews' axes: without it they have none.
    try {
        const auto fov = numbers_at(root, {"scene", "camera", "size"}, 2, file);
        g.camera = {fov[0], fov[1]};
    } catch (const std::runtime_error&) {
    }
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
                             const FeatureOptions& options, const std::vector<float>* reference) {
    FeatureOptions o = options;
    if (o.dark_block < 0) o.dark_block = automatic_dark_block(g.display);
    const FeatureImages f = compute_features(T, g.camera_columns, g.camera_rows, g.display, o, reference);
    write_feature_images(dir, f, g.camera);
    return f;
}

void write_feature_images(const std::string& dir, const FeatureImages& f, const ImageExtent& camera, bool previews,
                          io::CommitGroup* group) {
    const fs::path pngs = fs::path(dir) / "features";
    if (previews) fs::create_directories(pngs);
    // Pseudo colour, scaled so a 100-pixel-wide image is ~400 pixels wide.
    const int scale = std::max(1, 400 / std::max(1, f.width));
    // Every file is independent (and each is atomic), so they are drawn, compressed and fsync'ed
    // in parallel; the bytes do not depend on the order. A failure is rethrown after the others.
    // The two largest files come first, so that they do not start last and run alone.
    const std::size_t n = previews ? f.channels.size() : 0;
    tbb::parallel_for(std::size_t(0), n + 2, [&](std::size_t i) {
        if (i == 0) {
            write_exr((fs::path(dir) / "features.exr").string(), f.width, f.height, f.channels, group);
        } else if (i == 1) {
            write_npz_channels((fs::path(dir) / "features.npz").string(), f.width, f.height, f.channels, group);
        } else {
            const auto& [name, values] = f.channels[i - 2];
            write_pseudo_colour_png((pngs / (name + ".png")).string(), values, f.width, f.height, feature_title(name),
                                    NAN, NAN, scale, camera, group);
        }
    });
}

}  // namespace ltm::app
