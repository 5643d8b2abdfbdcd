#include "study/Dataset.h"

#include <fcntl.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <mutex>
#include "io/Json.h"
#include <sstream>
#include <thread>

#include "io/Image.h"
#include "features/Plot.h"
#include "io/AtomicFile.h"
#include "io/AtomicFolder.h"
#include "io/Checksum.h"
#include "scene/SceneSolid.h"
#include "study/Coco.h"
#include "study/DatasetCard.h"
#include "study/GroundTruth.h"
#include "study/Labels.h"
#include "study/Sampler.h"
#include "study/SceneRun.h"
#include "io/LtmFile.h"

namespace ltm {

namespace fs = std::filesystem;
using json = io::Json;

namespace {

// When this process started (static initialisation): a file temporary older than that in the
// dataset's own folders was left by a killed process, not by a concurrent shard still writing.
const fs::file_time_type kProcessStart = fs::file_time_type::clock::now();

// Removes the file temporaries (io::AtomicFile's names) that killed processes left in `folder`
// (index.jsonl, annotations.json, the card and its plots are written there atomically; a SIGKILL
// in mid-write leaves the temporary). Those of a concurrent writer are newer and are kept.
void remove_stale_file_temporaries(const fs::path& folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return;
    for (const auto& e : fs::directory_iterator(folder, ec)) {
        if (!io::AtomicFile::is_temporary_name(e.path().filename().string())) continue;
        const auto written = fs::last_write_time(e.path(), ec);
        if (!ec && written < kProcessStart) fs::remove(e.path(), ec);
    }
}

constexpr const char* kChecksums = "SHA256SUMS";
constexpr const char* kFormat = "ltmsim dataset 1";

std::string read_text(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + p.string());
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// The files of a sample folder and their checksums, in `sha256sum` form, names sorted.
std::string checksum_file(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(folder))
        if (e.is_regular_file()) names.push_back(fs::relative(e.path(), folder).generic_string());
    std::sort(names.begin(), names.end());
    std::string out;
    for (const auto& n : names) out += io::sha256_file((folder / n).string()) + "  " + n + "\n";
    return out;
}

// Whether a finished sample folder is complete and intact: SHA256SUMS lists exactly its other
// files, each with its checksum. `files` receives the list (name -> checksum).
bool verify_sample(const fs::path& folder, std::vector<std::pair<std::string, std::string>>* files = nullptr) {
    std::error_code ec;
    const fs::path sums = folder / kChecksums;
    if (!fs::is_regular_file(sums, ec)) return false;
    std::string text;
    try {
        text = read_text(sums);
    } catch (const std::exception&) {
        return false;
    }
    std::vector<std::pair<std::string, std::string>> listed;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        if (line.size() < 67 || line.substr(64, 2) != "  ") return false;
        listed.emplace_back(line.substr(66), line.substr(0, 64));
    }
    std::vector<std::string> present;
    for (const auto& e : fs::recursive_directory_iterator(folder, ec))
        if (e.is_regular_file() && e.path().filename() != kChecksums)
            present.push_back(fs::relative(e.path(), folder).generic_string());
    std::sort(present.begin(), present.end());
    if (present.size() != listed.size()) return false;
    for (size_t i = 0; i < listed.size(); ++i) {
        if (listed[i].first != present[i]) return false;
        try {
            if (io::sha256_file((folder / listed[i].first).string()) != listed[i].second) return false;
        } catch (const std::exception&) {
            return false;
        }
    }
    if (files) *files = std::move(listed);
    return true;
}

// One line appended to failures.jsonl with a single write (O_APPEND: lines from concurrent shards
// do not interleave), then synced.
void append_line(const fs::path& file, const std::string& line) {
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0666);
    if (fd < 0) throw std::runtime_error("cannot append to " + file.string());
    const std::string s = line + "\n";
    const ssize_t n = ::write(fd, s.data(), s.size());
    ::fsync(fd);
    ::close(fd);
    if (n != static_cast<ssize_t>(s.size())) throw std::runtime_error("cannot append to " + file.string());
}

// What one sample did: its stages, or where and why it failed.
struct SampleOutcome {
    long index = 0;
    bool ok = false;
    std::string stage, reason;  // failures
    std::vector<Stage> stages;
    std::map<std::string, long> defects;
};

// Draws, renders and writes sample i into samples/<i> (atomically). Runs in the caller's task
// arena: the render shares its threads with the other samples in flight. `references`, if not
// null, holds the golden reference of the spec's object (the object does not vary: one entry).
SampleOutcome produce_sample(const DatasetSpec& spec, long i, const fs::path& samples, ReferenceCache* references) {
    SampleOutcome out;
    out.index = i;
    StageReport report;
    std::string stage = "draw";
    try {
        StageTimer t_draw(&report, "draw");
        const SampleDraw s = draw_sample(spec, i);
        t_draw.done(fmt::format("{} defect(s)", s.scene.defects.size()));
        const Scene& scene = s.scene;
        stage = "mesh";
        const Solid solid = build_solid(scene, &report, /*surfaces_only=*/true);
        stage = "render";
        SceneRunOptions so;
        so.representation = auto_representation(solid);
        so.threads = 0;  // the arena of the dataset run
        so.reference_cache = references;
        const SceneRun run = run_scene(scene, solid, so, &report);
        stage = "ground-truth";
        StageTimer t_gt(&report, "ground-truth");
        const GroundTruth gt = ground_truth(scene, run.render, spec.mask_fraction);
        t_gt.done("");
        stage = "write";
        StageTimer t_write(&report, "write");
        io::AtomicFolder folder((samples / sample_name(i)).string(), "sample folder");
        const fs::path dir(folder.path());
        const int N = scene.camera.resolution[0], M = scene.camera.resolution[1];
        io::write_file((dir / "scene.yaml").string(), s.scene_yaml, "scene file");
        write_exr((dir / "features.exr").string(), N, M, run.features.channels);
        write_npz_channels((dir / "features.npz").string(), N, M, run.features.channels);
        write_png16((dir / "mask.png").string(), N, M, gt.mask);
        io::write_file((dir / "labels.json").string(), sample_labels_json(spec, s, run, gt), "labels");
        if (spec.keep_ltm) write_ltm_npz((dir / "ltm.npz").string(), run.render.T);
        if (spec.previews) write_previews((dir / "previews").string(), run.features, gt,
                                          {scene.camera.size[0], scene.camera.size[1]});
        io::write_file((dir / kChecksums).string(), checksum_file(dir), "checksums");
        folder.commit();
        t_write.done("");
        for (const Defect& d : scene.defects) ++out.defects[to_string(d.type)];
        out.ok = true;
    } catch (const std::exception& e) {
        out.stage = stage;
        out.reason = e.what();
    }
    out.stages = report.stages();
    return out;
}

// The identity of a dataset folder.
json identity(const DatasetSpec& spec, const std::string& version) {
    json j;
    j["format"] = kFormat;
    j["ltmsim_version"] = version;
    j["spec_sha256"] = io::sha256_hex(spec.canonical);
    j["samples"] = spec.samples;
    j["seed"] = spec.seed;
    j["requested"] = requested_parameters(spec);
    return j;
}

// The folder is new, or was made from this very spec (the sample count may grow); else
// DatasetError. Returns whether dataset.json is to be (re)written.
bool check_folder(const DatasetSpec& spec, const DatasetOptions& o) {
    const fs::path dir(o.out), id = dir / "dataset.json";
    std::error_code ec;
    if (fs::exists(dir) && !fs::is_directory(dir)) throw DatasetError(fmt::format("{} exists and is not a folder", o.out));
    if (!fs::exists(id)) {
        if (fs::exists(dir) && !fs::is_empty(dir, ec))
            throw DatasetError(fmt::format(
                "{} holds files but no dataset.json: it is no ltmsim dataset folder; use a new or empty folder", o.out));
        return true;
    }
    const std::string sha = io::sha256_hex(spec.canonical);
    json theirs;
    try {
        theirs = io::read_json_file(id.string(), "dataset description");
    } catch (const std::exception& e) {
        throw DatasetError(fmt::format("{}: not a dataset description ({})", id.string(), e.what()));
    }
    if (theirs.value("format", "") != kFormat || theirs.value("spec_sha256", "") != sha)
        throw DatasetError(fmt::format("{} was made from a different spec (its dataset.json has spec_sha256 {}; {} gives {}); "
                                       "write this dataset to a new folder",
                                       o.out, theirs.value("spec_sha256", std::string("?")), spec.file, sha));
    return theirs.value("samples", 0L) != spec.samples;
}

void write_identity(const DatasetSpec& spec, const DatasetOptions& o) {
    const fs::path dir(o.out);
    fs::create_directories(dir / "samples");
    io::write_json_file((dir / "dataset.json").string(), identity(spec, o.version), "dataset description");
    if (!fs::exists(dir / "spec.yaml")) io::write_file((dir / "spec.yaml").string(), o.spec_text, "spec copy");
}

}  // namespace

void parse_shard(const std::string& text, int& shard, int& shards) {
    const auto slash = text.find('/');
    auto number = [&](const std::string& s, long& v) {
        if (s.empty() || s.size() > 9 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
            return false;
        v = std::stol(s);
        return true;
    };
    long k = 0, n = 0;
    if (slash == std::string::npos || !number(text.substr(0, slash), k) || !number(text.substr(slash + 1), n))
        throw DatasetError(fmt::format("--shard {}: expected K/N, two positive integers (e.g. 2/8)", text));
    if (n < 1) throw DatasetError(fmt::format("--shard {}: N must be at least 1", text));
    if (k < 1 || k > n) throw DatasetError(fmt::format("--shard {}: K must be in 1..{} (shards are numbered from 1)", text, n));
    shard = static_cast<int>(k);
    shards = static_cast<int>(n);
}

void check_spec_feasible(const DatasetSpec& spec, int shard, int shards) {
    for (long i = 0; i < spec.samples; ++i)
        if (i < kFeasibilitySamples || i % shards == shard - 1) (void)draw_sample(spec, i);
}

DatasetSummary run_dataset(const DatasetSpec& spec, const DatasetOptions& o) {
    const auto t0 = std::chrono::steady_clock::now();
    DatasetSummary sum;
    sum.total = spec.samples;
    const fs::path dir(o.out), samples = dir / "samples";
    std::error_code ec;
    const bool new_identity = check_folder(spec, o);

    // Which samples this shard owes, and what of them is there already.
    std::vector<long> mine;
    for (long i = o.shard - 1; i < spec.samples; i += o.shards) mine.push_back(i);
    sum.shard_samples = static_cast<long>(mine.size());
    std::vector<long> pending;
    if (fs::is_directory(samples)) {
        std::map<std::string, std::vector<fs::path>> temporaries;  // sample name -> its stale temporaries
        for (const auto& e : fs::directory_iterator(samples)) {
            const std::string n = e.path().filename().string();
            if (io::AtomicFolder::is_temporary_name(n)) temporaries[n.substr(1, n.find(".tmp-") - 1)].push_back(e.path());
        }
        for (long i : mine) {
            const std::string n = sample_name(i);
            const fs::path f = samples / n;
            const bool exists = fs::exists(f), stale = temporaries.count(n) > 0;
            if ((exists || stale) && !o.resume)
                throw DatasetError(fmt::format("{} already holds sample {} of this shard{}; pass --resume to continue it", o.out,
                                               i, exists ? "" : " (a partial one)"));
            for (const auto& t : temporaries[n]) fs::remove_all(t, ec);
            if (exists && verify_sample(f)) {
                ++sum.kept;
                continue;
            }
            if (exists) {
                fs::remove_all(f, ec);
                ++sum.redone;
            }
            pending.push_back(i);
        }
    } else {
        pending = mine;
    }
    if (new_identity) write_identity(spec, o);
    fs::create_directories(samples);

    // Render the samples, several at once in one task arena.
    const int threads = o.threads > 0 ? o.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const int jobs = o.jobs > 0 ? o.jobs : threads + 1;
    std::atomic<bool> stop{false};
    size_t next = 0;
    long done = sum.kept, failed = 0;
    // The samples share their object's reference (their scenes give the spec's seed as their
    // reference_seed, study/Sampler.h): rendered by the first samples in flight, then found. An
    // object that varies has one reference per sample, which nothing keeps.
    ReferenceCache references;
    ReferenceCache* const shared_reference = varied_object_keys(spec).empty() ? &references : nullptr;
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_pipeline(
            static_cast<size_t>(jobs),
            tbb::make_filter<void, long>(tbb::filter_mode::serial_in_order,
                                         [&](tbb::flow_control& fc) -> long {
                                             if (next >= pending.size() || stop) {
                                                 fc.stop();
                                                 return -1;
                                             }
                                             return pending[next++];
                                         }) &
                tbb::make_filter<long, SampleOutcome>(tbb::filter_mode::parallel,
                                                      [&](long i) { return produce_sample(spec, i, samples, shared_reference); }) &
                tbb::make_filter<SampleOutcome, void>(tbb::filter_mode::serial_out_of_order, [&](const SampleOutcome& r) {
                    for (const Stage& st : r.stages) {
                        if (!sum.stage_seconds.count(st.name)) sum.stage_order.push_back(st.name);
                        sum.stage_seconds[st.name] += st.seconds;
                    }
                    if (r.ok) {
                        ++sum.rendered;
                        ++done;
                        for (const auto& [k, n] : r.defects) sum.defects[k] += n;
                    } else {
                        ++sum.failed;
                        ++failed;
                        json line;
                        line["sample"] = r.index;
                        line["seed"] = mix_seed(spec.seed, static_cast<std::uint64_t>(r.index));
                        line["stage"] = r.stage;
                        line["reason"] = r.reason;
                        append_line(dir / "failures.jsonl", line.dump());
                        if (o.fail_fast) stop = true;
                    }
                    if (o.progress) o.progress(done, sum.shard_samples, failed);
                }));
    });
    sum.stopped = stop;

    // The whole dataset there: rebuild the index (every shard that finishes last does it; they
    // write the same bytes).
    bool complete = true;
    for (long i = 0; i < spec.samples && complete; ++i) complete = fs::is_directory(samples / sample_name(i));
    if (complete) {
        build_dataset_index(o.out);
        sum.indexed = true;
    }
    sum.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return sum;
}

IndexSummary build_dataset_index(const std::string& dir_text) {
    const fs::path dir(dir_text), id = dir / "dataset.json", samples = dir / "samples";
    if (!fs::is_regular_file(id))
        throw DatasetError(fmt::format("{}: no dataset.json: not an ltmsim dataset folder", dir_text));
    remove_stale_file_temporaries(dir);
    remove_stale_file_temporaries(dir / "card");
    json ident;
    try {
        ident = io::read_json_file(id.string(), "dataset description");
    } catch (const std::exception& e) {
        throw DatasetError(fmt::format("{}: not a dataset description ({})", id.string(), e.what()));
    }
    IndexSummary s;
    s.total = ident.value("samples", 0L);
    std::vector<json> labels;
    std::string index;
    for (long i = 0; i < s.total; ++i) {
        const fs::path f = samples / sample_name(i);
        if (!fs::is_directory(f)) {
            s.missing.push_back(i);
            continue;
        }
        std::vector<std::pair<std::string, std::string>> files;
        if (!verify_sample(f, &files)) {
            s.corrupt.push_back(i);
            continue;
        }
        json L = io::read_json_file((f / "labels.json").string(), "labels");
        json line;
        line["sample"] = i;
        line["folder"] = "samples/" + sample_name(i);
        line["split"] = L["split"];
        line["defects"] = L["defects"].size();
        json sums = json::object();
        for (const auto& [name, sha] : files) sums[name] = sha;
        line["sha256"] = sums;
        index += line.dump() + "\n";
        for (const auto& d : L["defects"]) ++s.defects[d["kind"].get<std::string>()];
        labels.push_back(std::move(L));
        ++s.present;
    }
    io::write_file((dir / "index.jsonl").string(), index, "dataset index");
    io::write_json_file((dir / "annotations.json").string(), coco_annotations(labels), "COCO annotations", -1);
    std::string spec_text;
    try {
        spec_text = read_text(dir / "spec.yaml");
    } catch (const std::exception&) {
    }
    write_dataset_card(dir.string(), ident, spec_text, labels, s.total, s.missing, s.corrupt);
    return s;
}

}  // namespace ltm
