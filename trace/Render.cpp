#include "trace/Render.h"

#include "io/Pages.h"

#include <tbb/parallel_for.h>
#include <tbb/task_group.h>
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

// What one block of pixels produced: its rows (their lengths, then their entries back to back),
// its path statistics and its defect counts. Kept per wave and reused, so a wave allocates only
// while its buffers still grow.
struct BlockRows {
    std::vector<std::int32_t> row_nnz;  // per item of the block
    std::vector<std::int32_t> columns;
    std::vector<float> values;
    PathStats stats;
    std::vector<DefectPaths> defects;
    void clear() {
        row_nnz.clear();
        columns.clear();
        values.clear();
        stats = PathStats{};
        defects.clear();
    }
};

}  // namespace

std::int32_t merge_row(std::vector<RowEntry>& entries, int spp, std::vector<std::int32_t>& columns,
                       std::vector<float>& values) {
    // Each distinct column's weights summed in sample order, then the columns in ascending order.
    // The entries accumulate in an open-addressing table, one probe sequence per entry, and only
    // the distinct columns are sorted: each column's sum is the same additions in the same order
    // (sample order) as a stable sort by column and a merge would make, without sorting every
    // entry (a stable sort of a 1024-sample row costs 5 % of a render: perf). Rows of up to kHashed
    // entries (a pixel's samples, unless its spp is large) use tables on the stack; longer ones
    // a thread's scratch, grown once.
    constexpr size_t kHashed = 256;
    const size_t n = entries.size();
    size_t cap = 16;  // a power of two, at least twice the entries: short probe sequences
    while (cap < 2 * n) cap <<= 1;
    std::int32_t slot_small[2 * kHashed], col_small[kHashed];
    std::uint64_t order_small[kHashed];
    double sum_small[kHashed];
    std::int32_t *slot = slot_small, *col = col_small;
    std::uint64_t* order = order_small;
    double* sum = sum_small;
    if (n > kHashed) {
        struct Scratch {
            std::vector<std::int32_t> slot, col;
            std::vector<std::uint64_t> order;
            std::vector<double> sum;
        };
        thread_local Scratch big;
        if (big.slot.size() < cap) big.slot.resize(cap);
        if (big.col.size() < n) {
            big.col.resize(n);
            big.order.resize(n);
            big.sum.resize(n);
        }
        slot = big.slot.data();
        col = big.col.data();
        order = big.order.data();
        sum = big.sum.data();
    }
    std::fill(slot, slot + cap, -1);
    std::int32_t u = 0;
    for (const RowEntry& e : entries) {
        size_t h = (static_cast<std::uint32_t>(e.column) * 2654435761u) & (cap - 1);  // Knuth's multiplicative hash
        while (slot[h] >= 0 && col[slot[h]] != e.column) h = (h + 1) & (cap - 1);
        if (slot[h] < 0) {
            slot[h] = u;
            col[u] = e.column;
            sum[u] = 0.0;
            // Sorted by column (a display pixel, >= 0), distinct: the key's high half decides.
            order[u] = static_cast<std::uint64_t>(e.column) << 32 | static_cast<std::uint32_t>(u);
            ++u;
        }
        sum[slot[h]] += e.weight;
    }
    std::sort(order, order + u);
    const size_t at = columns.size();
    columns.resize(at + static_cast<size_t>(u));
    values.resize(at + static_cast<size_t>(u));
    for (std::int32_t i = 0; i < u; ++i) {
        const auto k = static_cast<std::uint32_t>(order[i]);
        columns[at + static_cast<size_t>(i)] = col[k];
        values[at + static_cast<size_t>(i)] = static_cast<float>(sum[k] / spp);
    }
    return u;
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

    const bool streaming = opt.row_sink != nullptr && opt.max_matrix_bytes > 0;
    if (streaming && (pattern || opt.pixels))
        throw std::invalid_argument("render: streaming rows to a sink needs a full render of T (no pattern, no pixel subset)");

    RenderResult out;
    if (pattern) {
        out.image.assign(static_cast<size_t>(K), 0.0);
        out.image_stderr.assign(static_cast<size_t>(K), 0.0);
    }
    out.tracked_defects = opt.track_defects;
    const long blocks = (items + kBlock - 1) / kBlock;
    Progress progress(opt.progress, items, spp);

    // Waves: consecutive runs of blocks traced in parallel, then appended in block order. The
    // blocks themselves (kBlock pixels each, merged in block order) are what make the result
    // independent of threads; the wave length only sets how many blocks' rows wait in memory to be
    // appended (enough per thread that the barrier between waves costs little).
    const long arena_threads = opt.threads > 0 ? opt.threads : tbb::this_task_arena::max_concurrency();
    const long wave_blocks = std::max(256L, 16L * arena_threads);
    // Two waves' buffers: while one wave is traced in parallel, this thread appends the wave
    // before it (run_waves).
    std::vector<BlockRows> waves[2];
    waves[0].resize(static_cast<size_t>(std::min(blocks, wave_blocks)));
    waves[1].resize(static_cast<size_t>(std::min(std::max(0L, blocks - wave_blocks), wave_blocks)));

    auto render_block = [&](long b, BlockRows& br) {
        PathStats& stats = br.stats;
        std::vector<RowEntry> entries;
        entries.reserve(static_cast<size_t>(spp));
        // The branches of one batch of camera samples (one per sample with the sample
        // estimator); reused, so after the first samples no allocation happens per sample.
        std::vector<PathResult> branches;
        // A batch: up to Tracer::kBatch camera samples of the block's pixels in order, across
        // pixels when a pixel has fewer samples (packets fill at low spp), traced by one
        // Tracer::sample_packet and consumed in sample order: the same results as one at a time.
        Vec3 packet_o[Tracer::kBatch], packet_d[Tracer::kBatch];
        std::vector<Rng> packet_rng;
        packet_rng.reserve(Tracer::kBatch);
        size_t packet_end[Tracer::kBatch];
        long packet_k[Tracer::kBatch];  // each sample's camera pixel
        int packet_s[Tracer::kBatch];   // and its index among the pixel's samples
        int pn = 0;
        // The pixel being consumed: its entries (above), the defects its samples met from
        // br.defects[first_count] on, and the pattern's sums.
        size_t first_count = 0;
        double sum = 0, sum2 = 0;
        // One camera sample of pixel k, branches[b, e): its value for the pattern, its entries of
        // the row and the defects it met.
        const auto consume = [&](long k, size_t b0, size_t e0) {
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
                    auto& list = br.defects;
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
        // Pixel k's row (or pattern value), once its last sample is consumed.
        const auto finish = [&](long k) {
            if (opt.track_defects)
                std::sort(br.defects.begin() + static_cast<long>(first_count), br.defects.end(),
                          [](const DefectPaths& a, const DefectPaths& c) { return a.defect < c.defect; });
            if (pattern) {
                const double n = spp, mean = sum / n;
                out.image[static_cast<size_t>(k)] = mean;
                // Standard error of the mean from the unbiased sample variance.
                const double var = spp > 1 ? std::max(0.0, (sum2 - n * mean * mean) / (n - 1)) : 0.0;
                out.image_stderr[static_cast<size_t>(k)] = std::sqrt(var / n);
                return;
            }
            br.row_nnz.push_back(merge_row(entries, spp, br.columns, br.values));
        };
        const auto flush = [&] {
            branches.clear();
            tracer.sample_packet(pn, packet_o, packet_d, packet_rng.data(), stats, branches, packet_end);
            for (int i = 0; i < pn; ++i) {
                const long k = packet_k[i];
                if (packet_s[i] == 0) {  // a pixel begins
                    first_count = br.defects.size();
                    entries.clear();
                    sum = sum2 = 0;
                }
                consume(k, i == 0 ? 0 : packet_end[i - 1], packet_end[i]);
                if (packet_s[i] == spp - 1) finish(k);
            }
            packet_rng.clear();
            pn = 0;
        };
        for (long item = b * kBlock; item < std::min(items, (b + 1) * kBlock); ++item) {
            const long k = opt.pixels ? (*opt.pixels)[static_cast<size_t>(item)] : item;
            for_each_camera_sample(cam, seed, k, [&](int s, Rng& rng, const Vec3& o, const Vec3& d) {
                packet_o[pn] = o;
                packet_d[pn] = d;
                packet_k[pn] = k;
                packet_s[pn] = s;
                packet_rng.push_back(rng);
                if (++pn == Tracer::kBatch) flush();
            });
        }
        if (pn > 0) flush();
        progress.add(std::min(items, (b + 1) * kBlock) - b * kBlock);
    };

    // T as it is assembled: the row offsets (whole) and the entries; once streaming, only the
    // current wave's rows, handed to the sink.
    // The entries' arrays are reserved once for the most entries the render can hold: one per
    // branch a camera sample ends in (one with the sample estimator, at most 2^split_depth with
    // the split one), and no more than the budget lets it hold before it streams (plus one wave).
    // A reservation's pages are mapped only as they are written (in huge pages, 2 MiB at a time),
    // so memory is what T fills; the arrays never grow by copying (unless a render without a
    // budget outgrows kUnbudgeted), and a whole T is moved out at the end, not copied: a copy's
    // first touches of fresh pages would be most of the serial time of a short render.
    std::vector<std::int32_t> held_indices;
    std::vector<float> held_data;
    std::vector<std::int64_t> indptr;
    if (!pattern) {
        indptr.reserve(static_cast<size_t>(K) + 1);
        indptr.push_back(0);
        const TracingDesc& tracing = scene.tracing;
        const double branches = tracing.estimator == Estimator::Split ? std::ldexp(1.0, tracing.split_depth) : 1.0;
        const double per_wave = branches * spp * static_cast<double>(wave_blocks * kBlock);
        constexpr double kUnbudgeted = double(std::size_t(1) << 27);  // entries: 512 MiB per array
        const double cap = streaming ? static_cast<double>(opt.max_matrix_bytes) / 8.0 + per_wave : kUnbudgeted;
        const double most = std::min(branches * spp * static_cast<double>(items), cap);
        // In huge pages when large (io/Pages.h): T's arrays are most of the fresh memory a
        // render touches. (Once streaming, the arrays are refilled without the advice.)
        io::reserve_in_huge_pages(held_indices, static_cast<size_t>(most));
        io::reserve_in_huge_pages(held_data, static_cast<size_t>(most));
    }
    std::int64_t sent_rows = 0;  // rows already given to the sink
    std::size_t total_nnz = 0;
    CsrMatrix block;             // a wave's rows for the sink (reused)
    block.cols = L;
    const auto held_bytes = [&] {
        return 8.0 * static_cast<double>(held_indices.size()) + 8.0 * static_cast<double>(indptr.size());
    };
    // Hands the held rows [sent_rows, indptr.size() - 1 + sent_rows) to the sink in pieces of at
    // most kPiece entries (a wave's worth; a longer row goes alone), and keeps none: copying what
    // was held when the budget was reached costs 2 MiB beyond it, not a second copy of it.
    constexpr std::int64_t kPiece = std::int64_t(1) << 18;
    const auto send_held = [&] {
        const std::int64_t rows_held = static_cast<std::int64_t>(indptr.size()) - 1;
        std::int64_t r0 = 0;
        while (r0 < rows_held) {
            std::int64_t r1 = r0 + 1;
            while (r1 < rows_held && indptr[static_cast<size_t>(r1 + 1)] - indptr[static_cast<size_t>(r0)] <=
                                         kPiece)
                ++r1;
            const auto from = static_cast<size_t>(indptr[static_cast<size_t>(r0)]);
            const auto n = static_cast<size_t>(indptr[static_cast<size_t>(r1)]) - from;
            block.rows = r1 - r0;
            block.indptr.resize(static_cast<size_t>(block.rows) + 1);
            for (std::int64_t r = r0; r <= r1; ++r)
                block.indptr[static_cast<size_t>(r - r0)] = indptr[static_cast<size_t>(r)] - static_cast<std::int64_t>(from);
            block.indices.resize(n);
            block.data.resize(n);
            std::copy_n(held_indices.data() + from, n, block.indices.data());
            std::copy_n(held_data.data() + from, n, block.data.data());
            opt.row_sink->rows(sent_rows + r0, block);
            r0 = r1;
        }
        sent_rows += rows_held;
        // Released, not kept: from now on the arrays hold one wave's rows at a time.
        std::vector<std::int32_t>().swap(held_indices);
        std::vector<float>().swap(held_data);
        indptr.assign(1, 0);
    };

    // A traced wave's blocks in block order: statistics, defect counts, rows (and, once over the
    // budget, the rows to the sink).
    const auto append_wave = [&](long w0, std::vector<BlockRows>& wave) {
        const long w1 = std::min(blocks, w0 + wave_blocks);
        for (long b = w0; b < w1; ++b) {
            BlockRows& br = wave[static_cast<size_t>(b - w0)];
            out.stats.merge(br.stats);
            out.defect_paths.insert(out.defect_paths.end(), br.defects.begin(), br.defects.end());
            if (pattern) continue;
            size_t at = 0;
            for (long item = b * kBlock; item < std::min(items, (b + 1) * kBlock); ++item) {
                const long k = opt.pixels ? (*opt.pixels)[static_cast<size_t>(item)] : item;
                // Rows outside the pixel subset stay empty.
                while (sent_rows + static_cast<std::int64_t>(indptr.size()) - 1 < k) indptr.push_back(indptr.back());
                const auto n = static_cast<size_t>(br.row_nnz[static_cast<size_t>(item - b * kBlock)]);
                held_indices.insert(held_indices.end(), br.columns.data() + at, br.columns.data() + at + n);
                held_data.insert(held_data.end(), br.values.data() + at, br.values.data() + at + n);
                indptr.push_back(indptr.back() + static_cast<std::int64_t>(n));
                at += n;
                total_nnz += n;
            }
        }
        if (streaming && (out.streamed || held_bytes() > static_cast<double>(opt.max_matrix_bytes))) {
            out.streamed = true;
            send_held();
        }
    };
    // Each wave is traced in parallel while this thread appends the wave before it (the copy of
    // its rows is serial, and mostly first touches of T's pages), then joins the tracing; only
    // the last wave's append is left alone at the end. Appends stay in wave and block order.
    const auto run_waves = [&] {
        long pending = -1;  // the first block of the traced wave not yet appended
        for (long w0 = 0; w0 < blocks; w0 += wave_blocks) {
            const long w1 = std::min(blocks, w0 + wave_blocks);
            std::vector<BlockRows>& wave = waves[(w0 / wave_blocks) % 2];
            for (long b = w0; b < w1; ++b) wave[static_cast<size_t>(b - w0)].clear();
            tbb::task_group tracing;
            tracing.run([&] { tbb::parallel_for(w0, w1, [&](long b) { render_block(b, wave[static_cast<size_t>(b - w0)]); }); });
            if (pending >= 0) {
                try {
                    append_wave(pending, waves[(pending / wave_blocks) % 2]);
                } catch (...) {
                    tracing.cancel();
                    tracing.wait();
                    throw;
                }
            }
            tracing.wait();
            pending = w0;
        }
        if (pending >= 0) append_wave(pending, waves[(pending / wave_blocks) % 2]);
    };
    if (opt.threads > 0) {
        tbb::task_arena arena(opt.threads);
        arena.execute(run_waves);
    } else {
        run_waves();
    }
    for (auto& w : waves) std::vector<BlockRows>().swap(w);

    const auto t_merge = std::chrono::steady_clock::now();
    out.trace_seconds = std::chrono::duration<double>(t_merge - t0).count();
    if (!pattern) {
        while (sent_rows + static_cast<std::int64_t>(indptr.size()) - 1 < K) indptr.push_back(indptr.back());
        out.nnz = total_nnz;
        if (out.streamed) {
            if (indptr.size() > 1) send_held();
        } else {
            CsrMatrix& T = out.T;
            T.rows = K;
            T.cols = L;
            T.indptr = std::move(indptr);
            T.indices = std::move(held_indices);
            T.data = std::move(held_data);
        }
    }
    const auto t_end = std::chrono::steady_clock::now();
    out.merge_seconds = std::chrono::duration<double>(t_end - t_merge).count();
    out.seconds = std::chrono::duration<double>(t_end - t0).count();
    return out;
}

}  // namespace ltm
