#pragma once
// COCO instance segmentation (Lin et al. 2014, cocodataset.org/#format-data): run-length encoded
// masks as COCO's own tools write them, so pycocotools and the tools built on it read
// annotations.json unchanged.
//
// RLE: the binary mask (h x w) read in column-major order (down each column, columns left to
// right, as COCO's maskApi does), as alternating run lengths starting with a run of zeros (which
// may be 0). The compressed string form (maskApi.c rleToString): each count, minus the count two
// before it from the third on, in 5-bit groups least significant first, each group + 48 as one
// ASCII character, bit 0x20 set while more groups follow, the sign read from bit 0x10 of the last.
#include <cstdint>
#include <string>
#include <vector>

namespace ltm {

// Run lengths of (mask == value) in COCO's column-major order; `mask` is row-major (width x height).
std::vector<std::uint32_t> coco_rle_counts(const std::vector<std::uint16_t>& mask, int width, int height,
                                           std::uint16_t value);

// The compressed string of RLE counts (rleToString), and its inverse (rleFrString).
std::string coco_rle_string(const std::vector<std::uint32_t>& counts);
std::vector<std::uint32_t> coco_rle_decode(const std::string& s);

}  // namespace ltm
