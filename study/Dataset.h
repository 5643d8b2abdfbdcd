#pragma once
// `ltmsim dataset`: a labelled dataset of sampled scenes, written so that nothing is lost and
// nothing is corrupt whatever happens to the process (docs/dataset.md).
//
// DIR/
//   dataset.json            what the folder was made from: the canonical spec's SHA-256, the
//                           sample count, the ltmsim version. A run with another spec is refused.
//   spec.yaml               the spec file as given (the first run's copy)
//   samples/<i:06d>/        one folder per finished sample, renamed into place whole
//                           (io/AtomicFolder.h): scene.yaml, features.exr, features.npz, mask.png,
//                           labels.json, [ltm.npz], [previews/*.png], and SHA256SUMS (the
//                           checksums of the others, in `sha256sum -c` form)
//   failures.jsonl          one line per failed attempt: sample, stage, reason
//   index.jsonl, annotations.json, README.md, card/*.png   rebuilt from the sample folders
//                           (build_dataset_index) when every sample is there, or on request
//
// Determinism: sample i is drawn by study/Sampler.h from (spec, i) alone, rendered with the seed
// of its scene file, and written by deterministic writers, so its bytes do not depend on the
// shard, the threads, the samples rendered beside it or an earlier interruption.
// Resume: a sample folder whose files match its SHA256SUMS is kept; any other (a corrupt file, a
// missing checksum file) and any temporary folder of the shard's samples is removed and redone.
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "study/DatasetSpec.h"

namespace ltm {

// Bad input found before any rendering (the output folder is another spec's, samples exist
// without --resume, a bad shard): the message, exit status 2, nothing written.
struct DatasetError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct DatasetOptions {
    std::string out;          // DIR
    std::string spec_text;    // the spec file as given (DIR/spec.yaml)
    std::string version;      // of ltmsim, recorded in DIR/dataset.json
    int shard = 1, shards = 1;  // --shard K/N: samples i = K - 1 (mod N)
    bool resume = false;
    bool fail_fast = false;
    int threads = 0;          // 0: all cores
    int jobs = 0;             // samples in flight at once; 0: max(2, threads)
    // Called after every finished or failed sample (from one thread at a time).
    std::function<void(long done, long total, long failed)> progress;
};

struct DatasetSummary {
    long total = 0;            // samples of the dataset
    long shard_samples = 0;    // of them in this shard
    long kept = 0;             // already complete (resume)
    long redone = 0;           // partial or corrupt, redone
    long rendered = 0;         // finished in this run
    long failed = 0;
    std::map<std::string, long> defects;         // per kind, over the samples rendered
    std::map<std::string, double> stage_seconds; // summed over the samples rendered
    std::vector<std::string> stage_order;        // the stages in the order they first ran
    double seconds = 0;
    bool indexed = false;      // the dataset was complete and index.jsonl etc. were rebuilt
    bool stopped = false;      // --fail-fast stopped the run
};

// Parses "K/N" (1 <= K <= N); DatasetError naming the flag otherwise.
void parse_shard(const std::string& text, int& shard, int& shards);

// Draws the shard's samples and the dataset's first kFeasibilitySamples (about a millisecond each,
// against a fraction of a second to render one) so that a spec that cannot be met fails before
// any rendering, the same way in every shard; throws InputError at the spec entry.
inline constexpr long kFeasibilitySamples = 1000;
void check_spec_feasible(const DatasetSpec& spec, int shard = 1, int shards = 1);

DatasetSummary run_dataset(const DatasetSpec& spec, const DatasetOptions& options);

struct IndexSummary {
    long total = 0;                 // samples the dataset should have
    long present = 0;               // complete, checksums verified
    std::vector<long> missing;      // not (yet) there
    std::vector<long> corrupt;      // a folder whose files do not match its checksums
    std::map<std::string, long> defects;  // per kind
};

// Rebuilds DIR/index.jsonl, DIR/annotations.json, DIR/README.md and DIR/card/*.png from the sample
// folders that are complete (each file checked against SHA256SUMS). DatasetError if DIR is no
// dataset folder.
IndexSummary build_dataset_index(const std::string& dir);

}  // namespace ltm
