#include "study/SceneRun.h"

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "io/PeakRss.h"
#include "trace/Rng.h"

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

// The rows of the reference's render reduced to their mean display positions as they arrive
// (in row order, from the render's appending thread): 2 floats per camera pixel.
class ReferenceMeans : public RowSink {
public:
    ReferenceMeans(const DisplayGrid& display, long pixels)
        : display_(display), mean(2 * static_cast<size_t>(pixels), std::numeric_limits<float>::quiet_NaN()) {}

    void rows(std::int64_t first_row, const CsrMatrix& block) override {
        std::vector<long> rows(static_cast<size_t>(block.rows));
        std::iota(rows.begin(), rows.end(), 0L);
        const std::vector<float> m = mean_positions(block, rows, display_, FeatureOptions{}.threshold);
        std::copy(m.begin(), m.end(), mean.begin() + 2 * first_row);
    }

private:
    DisplayGrid display_;

public:
    std::vector<float> mean;
};

}  // namespace

Representation auto_representation(const Solid& solid) {
    return Tracer::analytic_supported(solid, nullptr) ? Representation::Analytic : Representation::Refined;
}

DisplayGrid display_grid(const Scene& s) {
    return {s.display.resolution[0], s.display.resolution[1], s.display.size[0], s.display.size[1]};
}

FeatureOptions resolved_feature_options(const Scene& s, FeatureOptions o) {
    if (o.dark_block < 0) o.dark_block = automatic_dark_block(display_grid(s));
    return o;
}

namespace {

// The seed the reference's seed is mixed from: the scene's reference_seed if it gives one, else its
// render seed.
std::uint64_t reference_base_seed(const Scene& scene, const RenderOptions& options) {
    return scene.reference_seed ? *scene.reference_seed : render_seed(scene, options);
}

}  // namespace

std::uint64_t reference_seed(const Scene& scene, const RenderOptions& options) {
    return mix_seed(reference_base_seed(scene, options), kReferenceStream);
}

std::vector<float> defect_free_reference(const Scene& scene, Representation representation, const RenderOptions& options,
                                         long* rendered_pixels, ReferenceCache* cache, long* reused_pixels) {
    const long K = static_cast<long>(scene.camera.resolution[0]) * scene.camera.resolution[1];
    if (rendered_pixels) *rendered_pixels = 0;
    if (reused_pixels) *reused_pixels = 0;
    const Representation ref_rep = reference_representation(representation);
    const std::string key = cache ? ReferenceCache::key(scene, reference_seed(scene, options), ref_rep) : std::string();
    if (cache) {
        if (std::optional<std::vector<float>> found = cache->find(key)) {
            if (reused_pixels) *reused_pixels = K;
            return std::move(*found);
        }
    }
    // The defect-free scene whose render seed is reference_seed: its own seed is
    // reference_base_seed, mixed with kReferenceStream by RenderOptions::stream.
    Scene free = defect_free(scene);
    free.seed = reference_base_seed(scene, options);
    const Solid free_solid = build_solid(free, nullptr, representation != Representation::MeshOnly);
    TracerOptions o;
    o.representation = ref_rep;
    RenderOptions ro;
    ro.threads = options.threads;
    ro.stream = kReferenceStream;
    // Every row goes to the means as it passes (a budget of one byte streams them all): the
    // defect-free object's T is never held. The means are compute_features's MeanX and MeanY at
    // its default threshold.
    ReferenceMeans means(display_grid(scene), K);
    ro.row_sink = &means;
    ro.max_matrix_bytes = 1;
    render(Tracer(free, free_solid, o), ro);
    if (rendered_pixels) *rendered_pixels = K;
    if (cache) cache->store(key, means.mean);
    return std::move(means.mean);
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
    out.reference = defect_free_reference(scene, options.representation, ro, &out.reference_pixels, options.reference_cache,
                                          &out.reference_reused);
    add_deflection(out.features, out.reference);
    t_ref.done(out.reference_reused > 0
                   ? std::string("the defect-free object's, rendered for a scene before")
                   : fmt::format("the defect-free object, {} pixels, independent random numbers", out.reference_pixels));
    return out;
}

}  // namespace ltm
