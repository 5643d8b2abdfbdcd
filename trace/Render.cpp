#include "trace/Render.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>

namespace ltm {

namespace {

constexpr long kBlock = 32;  // pixels per block; fixed so block statistics merge in a fixed order

// Prints "rendering: 42% 3.1 Mpaths/s ETA 12 s" on a terminal, every half second.
class Progress {
public:
    Progress(bool enabled, long total_pixels, int spp)
        : enabled_(enabled && ::isatty(STDERR_FILENO)), total_(total_pixels), spp_(spp) {
        if (enabled_) thread_ = std::thread([this] { loop(); });
    }
    ~Progress() {
        if (!enabled_) return;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            stop_ = true;
        }
        cv_.notify_all();
        thread_.join();
        std::fprintf(stderr, "\r%60s\r", "");
    }
    void add(long pixels) { done_ += pixels; }

private:
    void loop() {
        const auto t0 = std::chrono::steady_clock::now();
        std::unique_lock<std::mutex> lock(mutex_);
        while (!cv_.wait_for(lock, std::chrono::milliseconds(500), [this] { return stop_; })) {
            const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            const long d = done_.load();
            const double rate = d * static_cast<double>(spp_) / std::max(s, 1e-9);
            const double eta = d > 0 ? s * (total_ - d) / d : 0.0;
            std::fprintf(stderr, "\rrendering: %3.0f%%  %.2f Mpaths/s  ETA %.0f s   ", 100.0 * d / total_, rate / 1e6, eta);
            std::fflush(stderr);
        }
    }
    bool enabled_;
    long total_;
    int spp_;
    std::atomic<long> done_{0};
    bool stop_ = false;
    std::mutex mutex_;
    std::condition_variable cv_;
    std::thread thread_;
};

}  // namespace

void merge_row(std::vector<RowEntry>& entries, int spp, std::vector<std::pair<std::int32_t, float>>& row) {
    // Merge equal columns, summing in sample order (the stable sort keeps it).
    std::stable_sort(entries.begin(), entries.end(), [](const RowEntry& a, const RowEntry& b) { return a.column < b.column; });
    for (size_t i = 0; i < entries.size();) {
        double w = 0;
        size_t j = i;
        for (; j < entries.size() && entries[j].column == entries[i].column; ++j) w += entries[j].weight;
        row.push_back({entries[i].column, static_cast<float>(w / spp)});
        i = j;
    }
}

std::uint64_t render_seed(const Scene& scene, const RenderOptions& options) {
    return options.stream == 0 ? scene.seed : mix_seed(scene.seed, options.stream);
}

RenderResult render(const Tracer& tracer, const RenderOptions& opt) {
    const auto t0 = std::chrono::steady_clock::now();
    const Scene& scene = tracer.scene();
    const TelecentricCamera& cam = tracer.camera();
    const long K = cam.pixels();
    const int spp = cam.samples_per_pixel();
    const long L = tracer.display().pixels();
    const std::uint64_t seed = render_seed(scene, opt);
    const bool pattern = opt.pattern != nullptr;
    const long items = opt.pixels ? static_cast<long>(opt.pixels->size()) : K;
    for (long i = 0; opt.pixels && i < items; ++i) {
        const long k = (*opt.pixels)[static_cast<size_t>(i)];
        if (k < 0 || k >= K || (i > 0 && k <= (*opt.pixels)[static_cast<size_t>(i - 1)]))
            throw std::invalid_argument("render: the pixel subset must be ascending camera pixels in [0, " +
                                        std::to_string(K) + ")");
    }

    if (pattern && static_cast<long>(opt.pattern->size()) != L)
        throw std::invalid_argument("the pattern has " + std::to_string(opt.pattern->size()) +
                                    " values but the display has " + std::to_string(L) + " pixels");

    RenderResult out;
    std::vector<std::vector<std::pair<std::int32_t, float>>> rows(pattern ? 0 : static_cast<size_t>(K));
    if (pattern) {
        out.image.assign(static_cast<size_t>(K), 0.0);
        out.image_stderr.assign(static_cast<size_t>(K), 0.0);
    }
    out.tracked_defects = opt.track_defects;
    const long blocks = (items + kBlock - 1) / kBlock;
    std::vector<PathStats> block_stats(static_cast<size_t>(blocks));
    std::vector<std::vector<DefectPaths>> block_defects(opt.track_defects ? static_cast<size_t>(blocks) : 0);
    Progress progress(opt.progress, items, spp);

    auto render_block = [&](long b) {
        PathStats& stats = block_stats[static_cast<size_t>(b)];
        std::vector<RowEntry> entries;
        entries.reserve(static_cast<size_t>(spp));
        // The branches of one packet of camera samples (one per sample with the sample
        // estimator); reused, so after the first samples no allocation happens per sample.
        std::vector<PathResult> branches;
        Vec3 packet_o[Tracer::kPacket], packet_d[Tracer::kPacket];
        std::vector<Rng> packet_rng;
        packet_rng.reserve(Tracer::kPacket);
        size_t packet_end[Tracer::kPacket];
        for (long item = b * kBlock; item < std::min(items, (b + 1) * kBlock); ++item) {
            const long k = opt.pixels ? (*opt.pixels)[static_cast<size_t>(item)] : item;
            const size_t first_count = opt.track_defects ? block_defects[static_cast<size_t>(b)].size() : 0;
            entries.clear();
            double sum = 0, sum2 = 0;
            // One camera sample's branches, branches[b, e): its value for the pattern, its
            // entries of the row and the defects it met.
            const auto consume = [&](size_t b0, size_t e0) {
                // The sample's value for the pattern: the sum of its branches' contributions.
                double f = 0;
                bool on_display = false;
                for (size_t i = b0; i < e0; ++i) {
                    const PathResult& r = branches[i];
                    // A sample met defect j first when one of its branches did; it counts once per
                    // defect, so the counts stay numbers of samples (study/GroundTruth.h).
                    const auto first_branch = branches.begin() + static_cast<long>(b0);
                    const auto earlier = branches.begin() + static_cast<long>(i);
                    if (opt.track_defects && r.defect >= 0 &&
                        std::none_of(first_branch, earlier, [&](const PathResult& e) { return e.defect == r.defect; })) {
                        auto& list = block_defects[static_cast<size_t>(b)];
                        auto it = std::find_if(list.begin() + static_cast<long>(first_count), list.end(),
                                               [&](const DefectPaths& e) { return e.defect == r.defect; });
                        if (it == list.end())
                            list.push_back({static_cast<std::int32_t>(k), r.defect, 1});
                        else
                            ++it->paths;
                    }
                    if (r.pixel < 0) continue;
                    on_display = true;
                    if (pattern)
                        f += r.weight * static_cast<double>((*opt.pattern)[static_cast<size_t>(r.pixel)]);
                    else
                        entries.push_back({static_cast<std::int32_t>(r.pixel), r.weight});
                }
                if (pattern && on_display) {
                    sum += f;
                    sum2 += f * f;
                }
            };
            // The pixel's samples in packets of Tracer::kPacket (Tracer::sample_packet), consumed
            // in sample order: the same results as one sample at a time.
            int pn = 0;
            const auto flush = [&] {
                branches.clear();
                tracer.sample_packet(pn, packet_o, packet_d, packet_rng.data(), stats, branches, packet_end);
                for (int i = 0; i < pn; ++i) consume(i == 0 ? 0 : packet_end[i - 1], packet_end[i]);
                packet_rng.clear();
                pn = 0;
            };
            for_each_camera_sample(cam, seed, k, [&](int, Rng& rng, const Vec3& o, const Vec3& d) {
                packet_o[pn] = o;
                packet_d[pn] = d;
                packet_rng.push_back(rng);
                if (++pn == Tracer::kPacket) flush();
            });
            if (pn > 0) flush();
            if (opt.track_defects) {
                auto& list = block_defects[static_cast<size_t>(b)];
                std::sort(list.begin() + static_cast<long>(first_count), list.end(),
                          [](const DefectPaths& a, const DefectPaths& c) { return a.defect < c.defect; });
            }
            if (pattern) {
                const double n = spp, mean = sum / n;
                out.image[static_cast<size_t>(k)] = mean;
                // Standard error of the mean from the unbiased sample variance.
                const double var = spp > 1 ? std::max(0.0, (sum2 - n * mean * mean) / (n - 1)) : 0.0;
                out.image_stderr[static_cast<size_t>(k)] = std::sqrt(var / n);
                continue;
            }
            merge_row(entries, spp, rows[static_cast<size_t>(k)]);
        }
        progress.add(std::min(items, (b + 1) * kBlock) - b * kBlock);
    };

    const auto all_blocks = [&] { tbb::parallel_for(0L, blocks, render_block); };
    if (opt.threads > 0) {
        tbb::task_arena arena(opt.threads);
        arena.execute(all_blocks);
    } else {
        all_blocks();
    }
    for (const auto& s : block_stats) out.stats.merge(s);
    for (auto& list : block_defects) {
        out.defect_paths.insert(out.defect_paths.end(), list.begin(), list.end());
        std::vector<DefectPaths>().swap(list);
    }

    const auto t_merge = std::chrono::steady_clock::now();
    out.trace_seconds = std::chrono::duration<double>(t_merge - t0).count();
    if (!pattern) {
        CsrMatrix& T = out.T;
        T.rows = K;
        T.cols = L;
        T.indptr.assign(static_cast<size_t>(K) + 1, 0);
        size_t nnz = 0;
        for (long k = 0; k < K; ++k) nnz += rows[static_cast<size_t>(k)].size();
        T.indices.reserve(nnz);
        T.data.reserve(nnz);
        for (long k = 0; k < K; ++k) {
            for (const auto& [c, v] : rows[static_cast<size_t>(k)]) {
                T.indices.push_back(c);
                T.data.push_back(v);
            }
            T.indptr[static_cast<size_t>(k) + 1] = static_cast<std::int64_t>(T.indices.size());
            std::vector<std::pair<std::int32_t, float>>().swap(rows[static_cast<size_t>(k)]);
        }
    }
    const auto t_end = std::chrono::steady_clock::now();
    out.merge_seconds = std::chrono::duration<double>(t_end - t_merge).count();
    out.seconds = std::chrono::duration<double>(t_end - t0).count();
    return out;
}

}  // namespace ltm
