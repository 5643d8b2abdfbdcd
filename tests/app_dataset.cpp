// `ltmsim dataset` end to end (study/Dataset.h, docs/dataset.md): the same bytes for a whole run,
// for shards, for any thread count and after kills and --resume; nothing partial after a kill;
// corrupt samples redone; another spec refused; failures logged; bad input located with exit
// status 2 and no output; the numpy loader; the index rebuilt; a sample re-rendered bit for bit.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <random>
#include <thread>

#include "io/Checksum.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;
using ltm::test::ltmsim;
using ltm::test::slurp;
using ltm::test::spit;

namespace {

// A small lens scene and a spec with every kind: samples of 20 x 20 pixels, 16 paths each.
const char* kBase = R"(object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
camera: {resolution: [20, 20], size: [25.0, 25.0], numerical_aperture: 0.01, samples_per_pixel: 16}
display: {resolution: [50, 50], size: [100.0, 100.0], z: 60.0}
)";

std::string spec(const std::string& extra = "", int samples = 8, int seed = 1) {
    return "scene: base.yaml\nsamples: " + std::to_string(samples) + "\nseed: " + std::to_string(seed) + R"(
defect_free_fraction: 0.15
defects:
  - {type: bubble, count: {poisson: 1.5}, radius: {log_uniform: [0.2, 1.0]}}
  - {type: scratch, count: {uniform_int: [0, 1]}, shape: {choice: [straight, arc]}, width: {uniform: [0.1, 0.3]}}
  - {type: particle, count: {uniform_int: [0, 1]}, semi_axes: [0.5, 0.3, 0.2]}
  - {type: inhomogeneity, count: {uniform_int: [0, 1]}, profile: uniform, delta_n: {uniform: [0.01, 0.02]}}
splits: {train: 0.75, test: 0.25}
)" + extra;
}

// Every file under `root` (relative path -> bytes).
std::map<std::string, std::string> tree(const fs::path& root) {
    std::map<std::string, std::string> t;
    if (!fs::exists(root)) return t;
    for (const auto& e : fs::recursive_directory_iterator(root))
        if (e.is_regular_file()) t[fs::relative(e.path(), root).generic_string()] = slurp(e.path());
    return t;
}

// The files that differ between two trees (or exist in one only).
std::vector<std::string> differences(const std::map<std::string, std::string>& a, const std::map<std::string, std::string>& b) {
    std::vector<std::string> d;
    for (const auto& [k, v] : a)
        if (!b.count(k) || b.at(k) != v) d.push_back(k);
    for (const auto& [k, v] : b)
        if (!a.count(k)) d.push_back(k + " (only in the second)");
    return d;
}

// Whether a finished sample folder matches its SHA256SUMS (each line "<hex>  <name>", the list
// being exactly its other files): checked here independently of the command's own check.
bool intact(const fs::path& folder) {
    std::istringstream in(slurp(folder / "SHA256SUMS"));
    std::map<std::string, std::string> listed;
    for (std::string line; std::getline(in, line);) listed[line.substr(66)] = line.substr(0, 64);
    std::size_t files = 0;
    for (const auto& e : fs::recursive_directory_iterator(folder))
        if (e.is_regular_file() && e.path().filename() != "SHA256SUMS") {
            ++files;
            const std::string name = fs::relative(e.path(), folder).generic_string();
            if (!listed.count(name) || listed[name] != ltm::io::sha256_file(e.path().string())) return false;
        }
    return files == listed.size() && files > 0;
}

class Dataset : public ltm::test::TempDirTest {
protected:
    void SetUp() override {
        TempDirTest::SetUp();
        spit(dir / "base.yaml", kBase);
        spit(dir / "spec.yaml", spec());
    }
    ltm::test::Outcome run(const std::string& args) { return ltmsim(args, dir); }
    std::string q(const fs::path& p) const { return "'" + p.string() + "'"; }
    // A dataset of spec.yaml in DIR/name, in one run.
    std::map<std::string, std::string> whole(const std::string& name, const std::string& flags = "--threads 2") {
        const auto r = run("dataset " + q(dir / "spec.yaml") + " -o " + q(dir / name) + " " + flags);
        EXPECT_EQ(r.status, 0) << r.out << r.err;
        return tree(dir / name);
    }
};

}  // namespace

TEST_F(Dataset, SameBytesWholeShardedAndWhateverTheThreads) {
    const auto full = whole("full");
    ASSERT_TRUE(full.count("index.jsonl"));
    ASSERT_TRUE(full.count("annotations.json"));
    ASSERT_TRUE(full.count("README.md"));
    ASSERT_TRUE(full.count("samples/000007/mask.png"));
    for (int i = 0; i < 8; ++i) EXPECT_TRUE(intact(dir / "full" / "samples" / ("00000" + std::to_string(i)))) << i;
    EXPECT_EQ(differences(full, whole("one-thread", "--threads 1 --jobs 1")), std::vector<std::string>{});
    EXPECT_EQ(differences(full, whole("four-jobs", "--threads 2 --jobs 4")), std::vector<std::string>{});
    // Three shards into one folder; the one that completes the dataset rebuilds the index.
    for (const char* s : {"2/3", "3/3", "1/3"}) {
        const auto r = run("dataset " + q(dir / "spec.yaml") + " -o " + q(dir / "shards") + " --shard " + s + " --threads 1");
        ASSERT_EQ(r.status, 0) << s << r.out << r.err;
        if (std::string(s) != "1/3") {
            EXPECT_NE(r.out.find("index: not yet"), std::string::npos) << r.out;
        }
    }
    EXPECT_EQ(differences(full, tree(dir / "shards")), std::vector<std::string>{});
    // The shard takes i = K - 1 (mod N): shard 2/3 of 8 samples owns 1, 4 and 7.
    fs::remove_all(dir / "two");
    ASSERT_EQ(run("dataset " + q(dir / "spec.yaml") + " -o " + q(dir / "two") + " --shard 2/3").status, 0);
    std::vector<std::string> owned;
    for (const auto& e : fs::directory_iterator(dir / "two" / "samples")) owned.push_back(e.path().filename().string());
    std::sort(owned.begin(), owned.end());
    EXPECT_EQ(owned, (std::vector<std::string>{"000001", "000004", "000007"}));
}

TEST_F(Dataset, KilledAtRandomMomentsThenResumedGivesTheSameBytes) {
    // Slower samples (40 x 40 pixels, 64 paths) so that kills land mid-run.
    spit(dir / "base.yaml", R"(object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
camera: {resolution: [40, 40], size: [25.0, 25.0], numerical_aperture: 0.01, samples_per_pixel: 64}
display: {resolution: [100, 100], size: [100.0, 100.0], z: 60.0}
)");
    const auto t0 = std::chrono::steady_clock::now();
    const auto full = whole("full");
    // Kill times drawn within the uninterrupted run's own duration, so that they land mid-run on
    // a fast machine as on a slow one.
    const double span_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const fs::path out = dir / "killed";
    std::mt19937 g(2024);
    int kills = 0;
    const std::string exe = ltm::test::ltmsim_exe(), s = (dir / "spec.yaml").string(), o = out.string();
    for (int round = 0; round < 12; ++round) {
        const pid_t pid = ::fork();
        ASSERT_GE(pid, 0);
        if (pid == 0) {
            const int null = ::open("/dev/null", O_WRONLY);
            ::dup2(null, 1);
            ::dup2(null, 2);
            ::execl(exe.c_str(), exe.c_str(), "dataset", s.c_str(), "-o", o.c_str(), "--resume", "--threads", "2", nullptr);
            ::_exit(127);
        }
        const double at = std::uniform_real_distribution<double>(0.05, 0.7)(g) * span_ms;
        std::this_thread::sleep_for(std::chrono::microseconds(static_cast<long>(1e3 * at)));
        ::kill(pid, SIGKILL);
        int status = 0;
        ::waitpid(pid, &status, 0);
        if (WIFSIGNALED(status)) ++kills;
        // Whatever the moment: every sample folder is whole, and nothing but samples and
        // temporaries is in samples/.
        if (fs::exists(out / "samples"))
            for (const auto& e : fs::directory_iterator(out / "samples")) {
                const std::string n = e.path().filename().string();
                if (n[0] == '.') {
                    EXPECT_NE(n.find(".tmp-"), std::string::npos) << n;
                    continue;
                }
                EXPECT_TRUE(intact(e.path())) << "round " << round << ": " << n << " is partial";
            }
        if (WIFEXITED(status)) break;  // it finished before the kill
    }
    EXPECT_GT(kills, 0);
    const auto r = run("dataset " + q(dir / "spec.yaml") + " -o " + q(out) + " --resume --threads 1");
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    auto resumed = tree(out);
    EXPECT_EQ(differences(full, resumed), std::vector<std::string>{});
}

TEST_F(Dataset, ResumeRedoesCorruptAndPartialSamplesOnly) {
    const auto full = whole("full");
    const fs::path out = dir / "copy";
    fs::copy(dir / "full", out, fs::copy_options::recursive);
    std::string bytes = slurp(out / "samples/000002/features.npz");
    bytes[bytes.size() / 2] ^= 1;
    spit(out / "samples/000002/features.npz", bytes);
    fs::remove(out / "samples/000003/labels.json");
    fs::create_directories(out / "samples/.000005.tmp-99999-0123456789abcdef");
    spit(out / "samples/.000005.tmp-99999-0123456789abcdef/features.exr", "partial");
    // Without --resume: refused, nothing touched.
    const auto before = tree(out);
    const auto refused = run("dataset " + q(dir / "spec.yaml") + " -o " + q(out));
    EXPECT_EQ(refused.status, 2);
    EXPECT_NE(refused.err.find("pass --resume"), std::string::npos) << refused.err;
    EXPECT_EQ(differences(before, tree(out)), std::vector<std::string>{});
    const auto r = run("dataset " + q(dir / "spec.yaml") + " -o " + q(out) + " --resume");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("(6 kept, 2 redone, 2 rendered, 0 failed)"), std::string::npos) << r.out;
    EXPECT_EQ(differences(full, tree(out)), std::vector<std::string>{});
}

TEST_F(Dataset, AFolderMadeFromAnotherSpecIsRefused) {
    whole("full");
    const auto before = tree(dir / "full");
    spit(dir / "other.yaml", spec("", 8, 2));
    const auto r = run("dataset " + q(dir / "other.yaml") + " -o " + q(dir / "full") + " --resume");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("was made from a different spec"), std::string::npos) << r.err;
    EXPECT_EQ(differences(before, tree(dir / "full")), std::vector<std::string>{});
    // The same spec with more samples grows the dataset: the first 8 are kept as they are.
    spit(dir / "more.yaml", spec("", 10, 1));
    const auto grown = run("dataset " + q(dir / "more.yaml") + " -o " + q(dir / "full") + " --resume");
    ASSERT_EQ(grown.status, 0) << grown.err;
    EXPECT_NE(grown.out.find("(8 kept, 0 redone, 2 rendered"), std::string::npos) << grown.out;
    const auto after = tree(dir / "full");
    for (const auto& [k, v] : before) {
        if (k.rfind("samples/", 0) != 0) continue;
        EXPECT_EQ(after.at(k), v) << k;
    }
}

TEST_F(Dataset, FailedSamplesAreLoggedAndTheRunGoesOn) {
    // Smooth inclusions with an index tolerance TetGen cannot meet within max_tets: every sample
    // that draws one fails at its mesh; the others are written.
    spit(dir / "base.yaml", std::string(kBase) + "mesh: {index_tolerance: 1.0e-9}\n");
    spit(dir / "spec.yaml", R"(scene: base.yaml
samples: 8
seed: 3
defects:
  - {type: bubble, count: 1, radius: 0.3}
  - {type: inhomogeneity, count: {uniform_int: [0, 1]}, profile: smooth, radius: 1.0}
)");
    const auto r = run("dataset " + q(dir / "spec.yaml") + " -o " + q(dir / "out"));
    EXPECT_EQ(r.status, 1) << r.out << r.err;
    const std::string log = slurp(dir / "out" / "failures.jsonl");
    std::istringstream in(log);
    int failures = 0, samples = 0;
    for (std::string line; std::getline(in, line);) {
        ++failures;
        EXPECT_NE(line.find("\"stage\":\"mesh\""), std::string::npos) << line;
        EXPECT_NE(line.find("max_tets"), std::string::npos) << line;
    }
    for (const auto& e : fs::directory_iterator(dir / "out" / "samples")) samples += e.path().filename().string()[0] != '.';
    EXPECT_GT(failures, 0);
    EXPECT_GT(samples, 0);
    EXPECT_EQ(failures + samples, 8);
    EXPECT_FALSE(fs::exists(dir / "out" / "index.jsonl"));  // incomplete: no index yet
    // --fail-fast stops at the first failure: fewer samples than the full run wrote.
    const auto ff = run("dataset " + q(dir / "spec.yaml") + " -o " + q(dir / "ff") + " --fail-fast --threads 1 --jobs 1");
    EXPECT_EQ(ff.status, 1);
    EXPECT_NE(ff.out.find("stopped at the first failure"), std::string::npos) << ff.out;
    int ff_samples = 0;
    for (const auto& e : fs::directory_iterator(dir / "ff" / "samples")) ff_samples += e.path().filename().string()[0] != '.';
    EXPECT_LT(ff_samples, samples);
}

TEST_F(Dataset, BadInputIsLocatedExitsWithTwoAndWritesNothing) {
    spit(dir / "bad-scene.yaml", "object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0}\n");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {spec().replace(spec().find("log_uniform"), 11, "logUniform"),
         "spec.yaml:6:52: defects[0].radius.logUniform: unknown distribution 'logUniform' (did you mean 'log_uniform'?)"},
        {spec().replace(spec().find("[0.2, 1.0]"), 10, "[-0.2, 1.0]"),
         "spec.yaml:6:65: defects[0].radius.log_uniform: a log-uniform range must be positive, got [-0.2, 1]"},
        {spec().replace(spec().find("[0.1, 0.3]"), 10, "[-0.1, 0.3]"),
         "defects[1].width.uniform: the range [-0.1, 0.3] holds values <= 0; this parameter must be positive"},
        {spec().replace(spec().find("[0.2, 1.0]"), 10, "[1.0, 0.2]"), "is empty"},
        {spec().replace(spec().find("{poisson: 1.5}"), 14, "{uniform_int: [0, 65]}"), "a count from 0 to 64"},
        {"scene: base.yaml\nsamples: 3\ndefects: [{type: bubble, radius: 5.0}]\nmax_attempts: 20\n",
         "spec.yaml:3:34: defects[0].radius: a bubble with radius 5 (sample 0) fits nowhere in the object: none of 20 "
         "positions holds it"},
        {"scene: bad-scene.yaml\nsamples: 3\ndefects: [{type: bubble, radius: 0.1}]\n",
         "bad-scene.yaml:1:9: object.ior: missing required key 'ior'"},
        {"scene:\n  object: {type: window, thickness: 0, diameter: 25.0, ior: 1.5}\nsamples: 3\ndefects: [{type: bubble}]\n",
         "spec.yaml:2:37: scene.object.thickness: must be a positive finite length (got 0)"},
    };
    for (const auto& [text, expected] : cases) {
        spit(dir / "spec.yaml", text);
        const auto r = run("dataset " + q(dir / "spec.yaml") + " -o " + q(dir / "out"));
        EXPECT_EQ(r.status, 2) << text << r.err;
        EXPECT_NE(r.err.find(expected), std::string::npos) << "expected: " << expected << "\ngot: " << r.err;
        EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line: " << r.err;
        EXPECT_FALSE(fs::exists(dir / "out")) << text;
    }
    spit(dir / "spec.yaml", spec());
    for (const char* shard : {"0/3", "4/3", "2", "a/b"}) {
        const auto r = run("dataset " + q(dir / "spec.yaml") + " -o " + q(dir / "out") + " --shard " + shard);
        EXPECT_EQ(r.status, 2) << shard;
        EXPECT_NE(r.err.find(std::string("--shard ") + shard), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir / "out"));
    }
}

TEST_F(Dataset, TheNumpyLoaderReadsSamplesAndTheCocoMasksAgree) {
    whole("full");
    if (!fs::exists("/usr/bin/python3")) LTM_INTEROP_SKIP() << "no /usr/bin/python3";
    // The loader (scripts/load_dataset.py) and the check need numpy (Debian: python3-numpy).
    if (std::system("/usr/bin/python3 -c 'import numpy' 2>/dev/null") != 0) LTM_INTEROP_SKIP() << "no numpy";
    // An independent decoder of COCO's compressed RLE (rleFrString, maskApi.c) and the checks.
    spit(dir / "check.py", R"PY(
import json, sys
import numpy as np
sys.path.insert(0, sys.argv[2])
from load_dataset import iterate, load_sample

def rle_decode(s):
    counts, p = [], 0
    while p < len(s):
        x, k, more = 0, 0, True
        while more:
            c = ord(s[p]) - 48; p += 1
            x |= (c & 0x1f) << (5 * k)
            more = bool(c & 0x20); k += 1
            if not more and (c & 0x10): x |= -1 << (5 * k)
        if len(counts) > 2: x += counts[-2]
        counts.append(x)
    return counts

def mask_of(counts, h, w):
    flat = np.zeros(h * w, dtype=bool); pos, on = 0, False
    for c in counts:
        flat[pos:pos + c] = on; pos += c; on = not on
    return flat.reshape(w, h).T        # column-major

root = sys.argv[1]
n = 0
for features, mask, labels in iterate(root):
    n += 1
    h, w = labels["image"]["height"], labels["image"]["width"]
    assert mask.shape == (h, w) and mask.dtype == np.uint16
    for name in ("BrightField", "ScatterCount", "ScatterWidth", "Deflection"):
        assert features[name].shape == (h, w) and features[name].dtype == np.float32, name
    assert mask.max() <= len(labels["defects"])
    for d in labels["defects"]:
        m = mask_of(rle_decode(d["segmentation"]["counts"]), h, w)
        assert (m == (mask == d["id"])).all(), d["id"]
        assert m.sum() == d["pixel_area"]
        if d["pixel_area"]:
            ys, xs = np.nonzero(m)
            assert d["bbox"] == [xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1]
coco = json.load(open(root + "/annotations.json"))
assert len(coco["images"]) == n == 8
ids = [a["id"] for a in coco["annotations"]]
assert len(ids) == len(set(ids))
assert {c["name"] for c in coco["categories"]} == {"bubble", "scratch", "particle", "inhomogeneity"}
train = sum(1 for _ in iterate(root, split="train"))
assert 0 < train < n, train
print("ok", n, len(ids))
)PY");
    const auto r = ltm::test::run_shell("/usr/bin/python3 " + q(dir / "check.py") + " " + q(dir / "full") + " " +
                                            q(fs::path(ltm::test::source_dir()) / "scripts"),
                                        dir);
    EXPECT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_EQ(r.out.rfind("ok 8", 0), 0u) << r.out;
}

TEST_F(Dataset, TheIndexIsRebuiltFromTheSampleFolders) {
    const auto full = whole("full");
    // The card compares every sampled parameter with its requested law (study/DatasetCard.h).
    const std::string card = full.at("README.md");
    EXPECT_NE(card.find("## Sampled parameters: requested and realised"), std::string::npos) << card;
    EXPECT_NE(card.find("| defects[0] bubble radius | {log_uniform: [0.2, 1]} | "), std::string::npos) << card;
    EXPECT_NE(card.find("| defects[1] scratch width | {uniform: [0.1, 0.3]} | "), std::string::npos) << card;
    EXPECT_NE(card.find("| defects[1] scratch shape | {choice: [straight, arc]} | "), std::string::npos) << card;
    for (const char* f : {"index.jsonl", "annotations.json", "README.md"}) fs::remove(dir / "full" / f);
    fs::remove_all(dir / "full" / "card");
    const auto r = run("dataset " + q(dir / "full") + " --index");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("8 of 8 samples present"), std::string::npos) << r.out;
    EXPECT_EQ(differences(full, tree(dir / "full")), std::vector<std::string>{});
    const auto no = run("dataset " + q(dir) + " --index");  // not a dataset folder
    EXPECT_EQ(no.status, 2);
}

TEST_F(Dataset, RenderingASamplesSceneReproducesItBitForBit) {
    whole("full");
    fs::create_directories(dir / "again");
    for (const char* i : {"000001", "000006"}) {
        const fs::path s = dir / "full" / "samples" / i;
        // Every sample is measured against the golden reference of the spec's seed (1).
        EXPECT_NE(slurp(s / "scene.yaml").find("\nreference_seed: 1\n"), std::string::npos) << i;
        const auto r = run("render " + q(s / "scene.yaml") + " -o " + q(dir / "again" / i) + " --threads 1");
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_EQ(slurp(dir / "again" / i / "features.exr"), slurp(s / "features.exr")) << i;
        EXPECT_EQ(slurp(dir / "again" / i / "features.npz"), slurp(s / "features.npz")) << i;
    }
}

TEST_F(Dataset, TheSlurmArrayScriptShardsTheDatasetAsOneRun) {
    // scripts/dataset-slurm.sh run as Slurm runs an array of 3 tasks numbered from 5: the
    // variables Slurm sets, the executable in LTMSIM.
    const auto full = whole("full");
    const std::string script = (fs::path(ltm::test::source_dir()) / "scripts" / "dataset-slurm.sh").string();
    for (int task : {6, 5, 7}) {
        const auto r = ltm::test::run_shell(
            "SLURM_ARRAY_TASK_ID=" + std::to_string(task) + " SLURM_ARRAY_TASK_MIN=5 SLURM_ARRAY_TASK_COUNT=3 "
                "SLURM_CPUS_PER_TASK=1 LTMSIM=" + ltm::test::ltmsim_exe() + " bash " + q(script) + " " + q(dir / "spec.yaml") + " " +
                q(dir / "slurm"),
            dir);
        ASSERT_EQ(r.status, 0) << task << r.out << r.err;
    }
    EXPECT_EQ(differences(full, tree(dir / "slurm")), std::vector<std::string>{});
    // Outside an array it says so.
    const auto no = ltm::test::run_shell("bash " + q(script) + " " + q(dir / "spec.yaml") + " " + q(dir / "x"), dir);
    EXPECT_NE(no.status, 0);
    EXPECT_NE(no.err.find("not a Slurm array task"), std::string::npos) << no.err;
}

TEST_F(Dataset, OptionalOutputsKeepTheMatrixAndWritePreviews) {
    spit(dir / "spec.yaml", spec("outputs: {ltm: true, previews: true}\n", 2));
    whole("full");
    for (const char* i : {"000000", "000001"}) {
        const fs::path s = dir / "full" / "samples" / i;
        EXPECT_TRUE(intact(s)) << i;  // the checksums cover the optional files too
        EXPECT_GT(fs::file_size(s / "ltm.npz"), 0u);
        EXPECT_TRUE(fs::exists(s / "previews" / "ScatterCount.png"));
        EXPECT_TRUE(fs::exists(s / "previews" / "mask.png"));
        EXPECT_NE(slurp(s / "SHA256SUMS").find("  previews/mask.png\n"), std::string::npos);
    }
}

TEST_F(Dataset, SmoothInhomogeneitiesAreMeshedTracedAndLabelled) {
    // A graded-index defect (TetGen per sample, coarse index tolerance to keep it quick): its
    // pixels are those whose paths pass where its index differs, about its disc of radius 1 to
    // 1.5 mm in 1.25 mm pixels.
    spit(dir / "base.yaml", std::string(kBase) + "mesh: {index_tolerance: 0.002}\n");
    spit(dir / "spec.yaml", "scene: base.yaml\nsamples: 2\ndefects:\n  - {type: inhomogeneity, count: 1, radius: "
                            "{uniform: [1.0, 1.5]}, delta_n: 0.01}\n");
    const auto r = run("dataset " + q(dir / "spec.yaml") + " -o " + q(dir / "g"));
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("tetgen"), std::string::npos) << r.out;  // the stage ran
    for (const char* i : {"000000", "000001"}) {
        const std::string labels = slurp(dir / "g" / "samples" / i / "labels.json");
        EXPECT_NE(labels.find("\"kind\": \"inhomogeneity\""), std::string::npos);
        EXPECT_EQ(labels.find("\"pixel_area\": 0,"), std::string::npos) << labels;
    }
}
