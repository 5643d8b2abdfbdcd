#include "study/SceneRun.h"

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <optional>
#include <stdexcept>

#include "io/PeakRss.h"

#include "scene/SceneSolid.h"

namespace ltm {

namespace {

// The rows of a streaming render: appended to ltm.npz's spill files (created at the first block,
// when the render has decided T does not fit) and turned into their features on the way.
class StreamedRows : public RowSink {
public:
    StreamedRows(const Scene& scene, const std::string& path, const FeatureOptions& options)
        : scene_(scene), path_(path), options_(options) {}

    void rows(std::int64_t first_row, const CsrMatrix& block) override {
        const long K = static_cast<long>(scene_.camera.resolution[0]) * scene_.camera.resolution[1];
        if (!file) {
            const std::filesystem::path folder = std::filesystem::path(path_).parent_path();
            if (!folder.empty()) std::filesystem::create_directories(folder);
            file = std::make_shared<LtmFileStream>(path_, K, static_cast<std::int64_t>(scene_.display.resolution[0]) *
                                                                 scene_.display.resolution[1]);
        }
        file->append(block);
        // A block's rows as a one-row "camera" of block.rows pixels: the features of each row are
        // the same whatever image the row sits in.
        const FeatureImages f =
            compute_features(block, static_cast<int>(block.rows), 1, display_grid(scene_), options_, nullptr);
        if (features.channels.empty()) {
            features.width = scene_.camera.resolution[0];
            features.height = scene_.camera.resolution[1];
            for (const auto& [name, values] : f.channels) features.channels.push_back({name, std::vector<float>(static_cast<size_t>(K))});
        }
        for (size_t c = 0; c < f.channels.size(); ++c)
            std::copy(f.channels[c].second.begin(), f.channels[c].second.end(),
                      features.channels[c].second.begin() + first_row);
    }

    std::shared_ptr<LtmFileStream> file;
    FeatureImages features;

private:
    const Scene& scene_;
    std::string path_;
    FeatureOptions options_;
};

}  // namespace

Representation auto_representation(const Solid& solid) {
    return Tracer::analytic_supported(solid, nullptr) ? Representation::Analytic : Representation::Refined;
}

DisplayGrid display_grid(const Scene& s) {
    return {s.display.resolution[0], s.display.resolution[1], s.display.size[0], s.display.size[1]};
}

FeatureOptions resolved_feature_options(const Scene& s, FeatureOptions o) {
    if (o.dark_block < 0) o.dark_block = std::min({60, s.display.resolution[0], s.display.resolution[1]});
    return o;
}

std::vector<float> defect_free_reference(const Scene& scene, const RenderResult& own, const std::vector<float>& mx,
                                         const std::vector<float>& my, Representation representation,
                                         const RenderOptions& options, long* rendered_pixels, ReferenceCache* cache,
                                         long* reused_pixels) {
    const long K = static_cast<long>(mx.size());
    std::vector<float> ref(2 * static_cast<size_t>(K));
    for (long k = 0; k < K; ++k) {
        ref[2 * static_cast<size_t>(k)] = mx[static_cast<size_t>(k)];
        ref[2 * static_cast<size_t>(k) + 1] = my[static_cast<size_t>(k)];
    }
    if (rendered_pixels) *rendered_pixels = 0;
    if (reused_pixels) *reused_pixels = 0;
    if (scene.defects.empty()) return ref;
    if (!own.tracked_defects)
        throw std::invalid_argument("defect_free_reference: the render must track its defects (RenderOptions::track_defects)");
    std::vector<long> met;
    for (const DefectPaths& e : own.defect_paths)
        if (met.empty() || met.back() != e.pixel) met.push_back(e.pixel);
    const Representation ref_rep = reference_representation(representation);
    const std::string key = cache ? ReferenceCache::key(scene, render_seed(scene, options), ref_rep) : std::string();
    if (cache) {
        const size_t all = met.size();
        met = cache->fill(key, met, K, ref);
        if (reused_pixels) *reused_pixels = static_cast<long>(all - met.size());
    }
    if (rendered_pixels) *rendered_pixels = static_cast<long>(met.size());
    if (met.empty()) return ref;
    const Scene free = defect_free(scene);
    const Solid free_solid = build_solid(free, nullptr, representation != Representation::MeshOnly);
    TracerOptions o;
    o.representation = ref_rep;
    RenderOptions ro = options;
    ro.pattern = nullptr;
    ro.progress = false;
    ro.track_defects = false;
    ro.pixels = &met;
    ro.row_sink = nullptr;  // a subset render keeps its small T
    const RenderResult free_render = render(Tracer(free, free_solid, o), ro);
    // The means of the traced rows alone (compute_features's MeanX and MeanY, at its default
    // threshold), not every channel of every pixel.
    const std::vector<float> m = mean_positions(free_render.T, met, display_grid(scene), FeatureOptions{}.threshold);
    for (size_t j = 0; j < met.size(); ++j) {
        ref[2 * static_cast<size_t>(met[j])] = m[2 * j];
        ref[2 * static_cast<size_t>(met[j]) + 1] = m[2 * j + 1];
    }
    if (cache) cache->store(key, met, K, ref);
    return ref;
}

Representation reference_representation(Representation r) {
    return r == Representation::MeshOnly ? Representation::MeshOnly : Representation::Analytic;
}

SceneRun run_scene(const Scene& scene, const Solid& solid, const SceneRunOptions& options, StageReport* report) {
    SceneRun out;
    out.representation = options.representation;
    StageTimer t_setup(report, "trace-setup");
    TracerOptions topt;
    topt.representation = options.representation;
    topt.robust = options.robust;
    const Tracer tracer(scene, solid, topt);
    t_setup.done(to_string(topt.representation));

    RenderOptions ro;
    ro.threads = options.threads;
    ro.progress = options.progress;
    ro.track_defects = true;
    const FeatureOptions feature_options = resolved_feature_options(scene, options.features);
    std::optional<StreamedRows> streamed;
    if (options.max_matrix_bytes > 0 && !options.stream_path.empty()) {
        streamed.emplace(scene, options.stream_path, feature_options);
        ro.row_sink = &*streamed;
        ro.max_matrix_bytes = options.max_matrix_bytes;
    }
    StageTimer t_render(report, "render");
    std::optional<io::PeakRssMeter> meter;
    if (options.measure_memory) meter.emplace();
    out.render = render(tracer, ro);
    ro.row_sink = nullptr;  // the reference's subset renders keep their small T
    if (meter) {
        out.render_memory = {true, meter->peak_bytes(), meter->start_bytes(), meter->per_run(), meter->method()};
    }
    const RenderResult& r = out.render;
    t_render.done(fmt::format("{} paths, {} segments, {:.3g} Mpaths/s{}", r.stats.paths, r.stats.segments,
                              r.stats.paths / std::max(r.seconds, 1e-9) / 1e6,
                              r.streamed ? fmt::format(", T streamed to {} ({} nonzeros, {} bytes, over the {}-byte budget)",
                                                       options.stream_path, r.nnz, 8 * r.nnz + 8 * (tracer.camera().pixels() + 1),
                                                       options.max_matrix_bytes)
                                         : std::string()));

    StageTimer t_features(report, "features");
    if (r.streamed) {
        out.features = std::move(streamed->features);  // computed block by block as the rows passed
        out.streamed_T = streamed->file;
    } else {
        out.features = compute_features(r.T, scene.camera.resolution[0], scene.camera.resolution[1], display_grid(scene),
                                        feature_options, nullptr);
    }
    t_features.done(fmt::format("{} channels{}", out.features.channels.size(), r.streamed ? ", from the streamed rows" : ""));

    StageTimer t_ref(report, "reference");
    out.reference = defect_free_reference(scene, r, out.features.channel("MeanX"), out.features.channel("MeanY"),
                                          options.representation, ro, &out.reference_pixels, options.reference_cache,
                                          &out.reference_reused);
    // A defect-free scene traced exactly as its reference would be (the same representation,
    // Embree's default traversal, every entry > 0 counted in the means) is every pixel's reference.
    if (options.reference_cache && scene.defects.empty() && options.representation == reference_representation(options.representation) &&
        options.robust == TracerOptions{}.robust && options.features.threshold == 0) {
        std::vector<long> all(static_cast<size_t>(out.reference.size() / 2));
        for (size_t k = 0; k < all.size(); ++k) all[k] = static_cast<long>(k);
        options.reference_cache->store(ReferenceCache::key(scene, render_seed(scene, ro), options.representation), all,
                                       static_cast<long>(all.size()), out.reference);
    }
    add_deflection(out.features, out.reference);  // exactly 0 for a defect-free scene (its own reference)
    t_ref.done(scene.defects.empty() ? std::string("the scene itself (defect-free)")
                                     : fmt::format("defect-free object at the {} pixels whose paths met a defect "
                                                   "({} more from the scenes before)",
                                                   out.reference_pixels, out.reference_reused));
    return out;
}

}  // namespace ltm
