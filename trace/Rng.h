#pragma once
// Counter-based random numbers: every (seed, pixel, sample) triple owns an independent stream, so
// results do not depend on which thread renders which pixel, nor in what order.
// The stream is PCG32 (O'Neill 2014, pcg32_random_r) seeded by SplitMix64 hashes of the triple.
#include <cstdint>

namespace ltm {

inline std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// A seed for stream `stream` of `seed`: splitmix64(seed + splitmix64(stream + c)). For a fixed
// stream it is a bijection of the seed, for a fixed seed a bijection of the stream (splitmix64
// and adding a constant are bijections of 64-bit words), and neighbouring inputs land far apart:
// unlike seed + stream, (seed, stream + 1) and (seed + 1, stream) do not collide.
inline std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream) {
    return splitmix64(seed + splitmix64(stream + 0xd1b54a32d192ed03ull));
}

class Rng {
public:
    // PCG32's multiplier, and the constants that set streams a and b apart in the seeding.
    static constexpr std::uint64_t kMultiplier = 6364136223846793005ull;
    static constexpr std::uint64_t kStreamA = 0x632be59bd9b4e019ull, kStreamB = 0x8cb92ba72f3d8dd7ull;

    Rng(std::uint64_t seed, std::uint64_t stream_a, std::uint64_t stream_b = 0) {
        const std::uint64_t h = splitmix64(splitmix64(seed) ^ splitmix64(stream_a + kStreamA) ^
                                           splitmix64(stream_b + kStreamB));
        inc_ = (splitmix64(h) << 1u) | 1u;
        state_ = 0;
        next_u32();
        state_ += h;
        next_u32();
    }
    // The stream of state 0 and increment 1, for arrays of streams each assigned before its first draw.
    Rng() = default;
    // The stream whose next draw follows `state` (with increment `inc`, odd): where a SIMD twin of
    // this class (trace/LaneKernels.h, the camera kernel) left a stream it drew from.
    static Rng from_state(std::uint64_t state, std::uint64_t inc) {
        Rng r;
        r.state_ = state;
        r.inc_ = inc;
        return r;
    }
    // The stream's state and increment, for a SIMD twin to draw from (from_state takes them back).
    std::uint64_t state() const { return state_; }
    std::uint64_t inc() const { return inc_; }
    std::uint32_t next_u32() {
        const std::uint64_t old = state_;
        state_ = old * kMultiplier + inc_;
        const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
        const auto rot = static_cast<std::uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
    }
    // Uniform in [0, 1) with 53 random bits.
    double uniform() {
        const std::uint64_t hi = next_u32(), lo = next_u32();
        return static_cast<double>(((hi << 32) | lo) >> 11) * 0x1.0p-53;
    }

private:
    std::uint64_t state_ = 0, inc_ = 1;
};

}  // namespace ltm
