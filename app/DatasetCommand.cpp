// `ltmsim dataset SPEC -o DIR [--shard K/N] [--resume]`: a labelled defect dataset drawn from a
// spec file (docs/dataset.md); `ltmsim dataset DIR --index` rebuilds its index, COCO annotations
// and card from the sample folders. The work is in study/Dataset.h.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>

#include "app/Commands.h"
#include "app/SceneSetup.h"
#include "io/InputError.h"
#include "scene/StrictYaml.h"
#include "study/Dataset.h"

namespace ltm::app {

namespace fs = std::filesystem;

namespace {

struct DatasetArgs {
    std::string input, out, shard = "1/1";
    bool resume = false, fail_fast = false, index = false;
    int threads = 0, jobs = 0;
};

// "dataset: 42/100 samples  1.93 samples/s  ETA 30 s" on a terminal, at most 5 times a second.
class Bar {
public:
    explicit Bar(long already) : tty_(::isatty(STDERR_FILENO) != 0), already_(already) {}
    void update(long done, long total, long failed) {
        if (!tty_) return;
        const auto now = std::chrono::steady_clock::now();
        if (done < total && now - last_ < std::chrono::milliseconds(200)) return;
        last_ = now;
        const double s = std::chrono::duration<double>(now - t0_).count();
        const double rate = (done - already_) / std::max(s, 1e-9);
        const double eta = rate > 0 ? (total - done) / rate : 0.0;
        std::fprintf(stderr, "\rdataset: %ld/%ld samples  %.2f samples/s  ETA %.0f s%s   ", done, total, rate, eta,
                     failed ? fmt::format("  {} failed", failed).c_str() : "");
        std::fflush(stderr);
    }
    ~Bar() {
        if (tty_) std::fprintf(stderr, "\n");
    }

private:
    bool tty_;
    long already_;
    std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now(), last_{};
};

std::string index_text(const IndexSummary& s, const std::string& dir) {
    std::string t = fmt::format("index of {}: {} of {} samples present", dir, s.present, s.total);
    if (!s.missing.empty()) t += fmt::format(", {} missing (first: {})", s.missing.size(), s.missing.front());
    if (!s.corrupt.empty()) t += fmt::format(", {} corrupt (first: {}; `--resume` redoes them)", s.corrupt.size(), s.corrupt.front());
    t += "\n  wrote index.jsonl, annotations.json, README.md, card/\n";
    for (const auto& [k, n] : s.defects) t += fmt::format("  {}: {} defects\n", k, n);
    return t;
}

int run(const DatasetArgs& a) {
    if (a.index) {
        try {
            std::cout << index_text(build_dataset_index(a.input), a.input);
        } catch (const DatasetError& e) {
            std::cerr << "ltmsim dataset: " << e.what() << "\n";
            return 2;
        }
        return 0;
    }
    if (a.out.empty()) {
        std::cerr << "ltmsim dataset: -o DIR is required (or --index to rebuild an existing dataset's index)\n";
        return 2;
    }
    DatasetOptions o;
    o.out = a.out;
    o.resume = a.resume;
    o.fail_fast = a.fail_fast;
    o.threads = a.threads;
    o.jobs = a.jobs;
    o.version = kVersion;
    DatasetSpec spec;
    try {
        parse_shard(a.shard, o.shard, o.shards);
        spec = load_dataset_spec(a.input);
        print_scene_warnings(spec.base);
        o.spec_text = yaml::read_file(a.input, "dataset spec");
        // The shard's samples are drawn now: a spec that cannot be met fails before anything is
        // rendered.
        check_spec_feasible(spec, o.shard, o.shards);
    } catch (const InputError& e) {
        std::cerr << e.what() << "\n";
        return 2;
    } catch (const DatasetError& e) {
        std::cerr << "ltmsim dataset: " << e.what() << "\n";
        return 2;
    }
    if (!output_folder_ok("dataset", a.out)) return 2;
    DatasetSummary s;
    {
        Bar bar(0);
        o.progress = [&bar](long done, long total, long failed) { bar.update(done, total, failed); };
        try {
            s = run_dataset(spec, o);
        } catch (const DatasetError& e) {
            std::cerr << "ltmsim dataset: " << e.what() << "\n";
            return 2;
        }
    }
    std::cout << fmt::format("dataset {}: shard {}/{}, {} of {} samples ({} kept, {} redone, {} rendered, {} failed) in "
                             "{:.1f} s, {:.2f} samples/s\n",
                             a.out, o.shard, o.shards, s.shard_samples, s.total, s.kept, s.redone, s.rendered, s.failed,
                             s.seconds, s.rendered / std::max(s.seconds, 1e-9));
    std::string kinds;
    for (const auto& [k, n] : s.defects) kinds += fmt::format(" {} {},", k, n);
    if (!kinds.empty()) kinds.pop_back();
    std::cout << "defects:" << (kinds.empty() ? " none" : kinds) << "\n";
    if (s.rendered + s.failed > 0) {
        std::cout << "time per stage (mean per sample; samples run concurrently):\n";
        const double n = static_cast<double>(s.rendered + s.failed);
        for (const auto& name : s.stage_order)
            std::cout << fmt::format("  {:<14} {:9.1f} ms\n", name, 1e3 * s.stage_seconds.at(name) / n);
    }
    if (s.failed) std::cout << fmt::format("failures: {} (see {}/failures.jsonl)\n", s.failed, a.out);
    if (s.stopped) std::cout << "stopped at the first failure (--fail-fast)\n";
    if (s.indexed)
        std::cout << "index: rebuilt index.jsonl, annotations.json and README.md (every sample is there)\n";
    else
        std::cout << fmt::format("index: not yet (samples missing); once every shard is done: ltmsim dataset {} --index\n",
                                 a.out);
    return s.failed > 0 ? 1 : 0;
}

}  // namespace

void add_dataset_command(CLI::App& app) {
    auto args = std::make_shared<DatasetArgs>();
    CLI::App* cmd = app.add_subcommand("dataset", "Generate a labelled defect dataset from a spec file (docs/dataset.md)");
    cmd->add_option("spec", args->input, "The dataset spec (YAML); with --index, the dataset folder")->required();
    cmd->add_option("-o,--output", args->out, "Output folder (created if missing; its parent must exist)");
    cmd->add_option("--shard", args->shard, "K/N: render only samples i = K-1 (mod N), for job arrays (default 1/1)");
    cmd->add_flag("--resume", args->resume, "Continue an interrupted run: keep verified samples, redo partial ones");
    cmd->add_flag("--fail-fast", args->fail_fast, "Stop at the first failed sample instead of logging it and going on");
    cmd->add_flag("--index", args->index, "Rebuild index.jsonl, annotations.json and README.md of the dataset folder");
    add_threads_option(cmd, args->threads, "Threads (default: all cores); results do not depend on it");
    cmd->add_option("--jobs", args->jobs, "Samples rendered at once (default: threads + 1); results do not depend on it")
        ->check(whole_number(0, kMaxInt, "threads + 1"));
    cmd->callback([args] { run_guarded("dataset", args->threads, [&] { return run(*args); }); });
}

}  // namespace ltm::app
