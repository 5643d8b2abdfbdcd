#pragma once
// The dataset card: DIR/README.md, what a dataset holds and how it was made (the spec, counts per
// kind and split, every sampled parameter's requested and realised distribution with a
// goodness-of-fit test, size histograms in DIR/card/*.png, how to load it), rebuilt with the index.
#include "io/Json.h"
#include <string>
#include <vector>

#include "study/DatasetSpec.h"

namespace ltm {

// What the spec asks for, for the card: the defect-free share, the splits, the laws of the
// object's varied keys, and per entry of `defects` its kind, count law and the law of every key
// the sampler draws (study/Sampler.h, sampled_keys). dataset.json keeps it as "requested":
//   {"defect_free_fraction": f, "splits": {name: share},
//    "object": [{"key": k, "law": L}], "defects": [{"entry": i, "kind": k, "count": "{poisson: 2}",
//                                                   "parameters": [{"key": k, "law": L}]}]}
// with L = {"spec": as the spec writes it, "law": constant | uniform | log_uniform | normal |
// choice, "a", "b", "range": any | positive | non-negative} (numbers) or {"spec", "law": "choice",
// "options": [...]} (words).
io::Json requested_parameters(const DatasetSpec& spec);

// `identity` is dataset.json (its "requested" above, when present); `labels` the samples'
// labels.json, whose "sampled" values are the realised draws.
void write_dataset_card(const std::string& dir, const io::Json& identity, const std::string& spec_text,
                        const std::vector<io::Json>& labels, long total, const std::vector<long>& missing,
                        const std::vector<long>& corrupt);

}  // namespace ltm
