#include "study/Coco.h"

#include <stdexcept>

namespace ltm {

std::vector<std::uint32_t> coco_rle_counts(const std::vector<std::uint16_t>& mask, int width, int height,
                                           std::uint16_t value) {
    if (mask.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
        throw std::invalid_argument("coco_rle_counts: the mask does not have width x height values");
    std::vector<std::uint32_t> counts;
    bool current = false;  // runs start with zeros
    std::uint32_t run = 0;
    for (int x = 0; x < width; ++x)
        for (int y = 0; y < height; ++y) {
            const bool on = mask[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)] == value;
            if (on != current) {
                counts.push_back(run);
                run = 0;
                current = on;
            }
            ++run;
        }
    counts.push_back(run);
    return counts;
}

std::string coco_rle_string(const std::vector<std::uint32_t>& counts) {
    std::string s;
    for (size_t i = 0; i < counts.size(); ++i) {
        long long x = counts[i];
        if (i > 2) x -= static_cast<long long>(counts[i - 2]);
        for (bool more = true; more;) {
            long long c = x & 0x1f;
            x >>= 5;  // arithmetic shift: a negative difference keeps its sign
            more = (c & 0x10) ? x != -1 : x != 0;
            if (more) c |= 0x20;
            s += static_cast<char>(c + 48);
        }
    }
    return s;
}

std::vector<std::uint32_t> coco_rle_decode(const std::string& s) {
    std::vector<std::uint32_t> counts;
    size_t p = 0;
    while (p < s.size()) {
        long long x = 0;
        int k = 0;
        for (bool more = true; more; ++k) {
            if (p >= s.size()) throw std::invalid_argument("coco_rle_decode: truncated string");
            const long long c = static_cast<long long>(s[p++]) - 48;
            x |= (c & 0x1f) << (5 * k);
            more = (c & 0x20) != 0;
            if (!more && (c & 0x10)) x |= static_cast<long long>(~0ULL << (5 * (k + 1)));  // sign-extend
        }
        if (counts.size() > 2) x += counts[counts.size() - 2];
        if (x < 0) throw std::invalid_argument("coco_rle_decode: negative run");
        counts.push_back(static_cast<std::uint32_t>(x));
    }
    return counts;
}

}  // namespace ltm
