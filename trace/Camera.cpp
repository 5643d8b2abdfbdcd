#include "trace/Camera.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "trace/LaneKernels.h"

namespace ltm {

void TelecentricCamera::sample_packet(long k, int s0, int n, const std::vector<int>& perm, std::uint64_t seed,
                                      Rng* rng, Vec3* origin, Vec3* dir) const {
    if (n < 0 || n > lanes::kRays) throw std::invalid_argument("TelecentricCamera::sample_packet: more than 16 samples");
    if (n == 0) return;
    // Rng(seed, k, s) hashes the seed and k the same way for every sample of the pixel: that part
    // once, the streams, their draws and the rays' arithmetic in lanes (lanes::seed_streams,
    // lanes::uniform; sample_from's operations in its order).
    lanes::CameraLanes c;
    c.key = splitmix64(seed) ^ splitmix64(static_cast<std::uint64_t>(k) + Rng::kStreamA);
    c.strata = grid_ > 0 ? grid_ : spp_;
    c.column = static_cast<double>(k % N_);
    c.row = static_cast<double>(k / N_);
    c.half_width = -0.5 * width_;
    c.half_height = 0.5 * height_;
    c.width = width_;
    c.height = height_;
    c.columns = N_;
    c.rows = M_;
    c.na = na_;
    c.focus_z = focus_z_;
    c.depth = focus_z_ - start_z_;
    const lanes::Kernels& kernels = lanes::kernels();
    const int count = kernels.count(n);
    for (int i = 0; i < count; ++i) {  // lanes past n repeat the last sample: finite, ignored
        const int s = s0 + std::min(i, n - 1);
        c.sample[i] = static_cast<std::uint64_t>(s);
        c.stratum_x[i] = grid_ > 0 ? s % grid_ : s;
        c.stratum_y[i] = grid_ > 0 ? s / grid_ : perm[static_cast<size_t>(s)];
    }
    kernels.camera(c, count);
    for (int i = 0; i < n; ++i) {
        origin[i] = c.origin.get(i);
        dir[i] = c.dir.get(i);
        rng[i] = Rng::from_state(c.state[i], c.inc[i]);
    }
}

}  // namespace ltm
