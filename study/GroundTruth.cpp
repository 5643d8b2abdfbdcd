#include "study/GroundTruth.h"

#include <algorithm>
#include <stdexcept>

namespace ltm {

GroundTruth ground_truth(const Scene& scene, const RenderResult& r, double min_fraction) {
    const int N = scene.camera.resolution[0], M = scene.camera.resolution[1];
    const long K = static_cast<long>(N) * M;
    const int D = static_cast<int>(scene.defects.size());
    const int spp = scene.camera.samples_per_pixel;
    if (!(min_fraction > 0 && min_fraction <= 1))
        throw std::invalid_argument("ground truth: min_fraction must be in (0, 1], got " + std::to_string(min_fraction));
    if (D > 65535)
        throw std::invalid_argument("ground truth: the scene has " + std::to_string(D) +
                                    " defects; a 16-bit mask holds at most 65535");
    if (!r.tracked_defects)
        throw std::invalid_argument("ground truth: the render did not track its defects (RenderOptions::track_defects)");
    GroundTruth g;
    g.width = N;
    g.height = M;
    g.min_fraction = min_fraction;
    g.mask.assign(static_cast<size_t>(K), 0);
    g.defects.resize(static_cast<size_t>(D));
    std::vector<std::array<int, 4>> box(static_cast<size_t>(D), {N, M, -1, -1});  // x0, y0, x1, y1
    for (int j = 0; j < D; ++j) {
        g.defects[static_cast<size_t>(j)].id = j + 1;
        g.defects[static_cast<size_t>(j)].kind = scene.defects[static_cast<size_t>(j)].type;
    }
    // defect_paths is sorted by pixel: one run of entries per pixel some path of which met a defect.
    const auto& e = r.defect_paths;
    for (size_t i = 0; i < e.size();) {
        const long k = e[i].pixel;
        size_t best = e.size();
        for (; i < e.size() && e[i].pixel == k; ++i) {
            if (e[i].defect < 0 || e[i].defect >= D || k < 0 || k >= K)
                throw std::invalid_argument("ground truth: the render's defect counts do not belong to this scene");
            DefectLabel& L = g.defects[static_cast<size_t>(e[i].defect)];
            const double f = static_cast<double>(e[i].paths) / spp;
            L.path_pixels += f;
            L.max_fraction = std::max(L.max_fraction, f);
            if (f < min_fraction) continue;
            ++L.footprint;
            if (best == e.size() || e[i].paths > e[best].paths) best = i;  // ties: the lower index (sorted)
        }
        if (best == e.size()) continue;
        const int j = e[best].defect;
        g.mask[static_cast<size_t>(k)] = static_cast<std::uint16_t>(j + 1);
        DefectLabel& L = g.defects[static_cast<size_t>(j)];
        ++L.pixel_area;
        const int x = static_cast<int>(k % N), y = static_cast<int>(k / N);
        auto& b = box[static_cast<size_t>(j)];
        b = {std::min(b[0], x), std::min(b[1], y), std::max(b[2], x), std::max(b[3], y)};
    }
    for (int j = 0; j < D; ++j) {
        DefectLabel& L = g.defects[static_cast<size_t>(j)];
        const auto& b = box[static_cast<size_t>(j)];
        if (L.pixel_area > 0) L.bbox = {b[0], b[1], b[2] - b[0] + 1, b[3] - b[1] + 1};
        L.visibility = L.footprint > 0 ? static_cast<double>(L.pixel_area) / static_cast<double>(L.footprint) : 0.0;
    }
    return g;
}

}  // namespace ltm
