#pragma once
// The dataset card: DIR/README.md, what a dataset holds and how it was made (the spec, counts per
// kind and split, size histograms in DIR/card/*.png, how to load it), rebuilt with the index.
#include "io/Json.h"
#include <string>
#include <vector>

namespace ltm {

void write_dataset_card(const std::string& dir, const io::Json& identity, const std::string& spec_text,
                        const std::vector<io::Json>& labels, long total, const std::vector<long>& missing,
                        const std::vector<long>& corrupt);

}  // namespace ltm
