#pragma once
// Counter-based random numbers: one independent stream per (seed, pattern, camera pixel), so a
// simulated acquisition is bit-identical whatever the number of threads or the order in which
// pixels are visited (no shared generator, no state carried from one pixel to the next).
//
// A stream's key is a mixing hash of its three indices; its i-th 64-bit draw is the mix of
// key + (i + 1) * phi64 (phi64 = 2^64 / golden ratio, odd, so the counters of one key never
// collide). The mixer is the SplitMix64 finaliser (G. L. Steele, D. Lea and C. H. Flood, "Fast
// splittable pseudorandom number generators", OOPSLA 2014; constants of D. Stafford's "Mix13"),
// a bijection of 64-bit words with full avalanche: SplitMix64 itself is exactly this
// construction with a single key, and passes BigCrush.
#include <cstdint>

namespace ltm::acquire {

inline std::uint64_t mix64(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

inline constexpr std::uint64_t kPhi64 = 0x9e3779b97f4a7c15ULL;

// The key of stream (seed, a, b): nested mixing, so (a, b) and (b, a) are different streams and a
// seed change moves every stream.
inline std::uint64_t stream_key(std::uint64_t seed, std::uint64_t a, std::uint64_t b) {
    return mix64(mix64(mix64(seed + kPhi64) ^ (a + 0x632be59bd9b4e019ULL)) ^ (b + 0x85ebca77c2b2ae63ULL));
}

class CounterRng {
public:
    CounterRng(std::uint64_t seed, std::uint64_t a, std::uint64_t b) : key_(stream_key(seed, a, b)) {}

    std::uint64_t next() { return mix64(key_ + (++counter_) * kPhi64); }
    // Uniform on the open interval (0, 1): the top 53 bits plus half a step, so neither 0 nor 1
    // (log(u) is always finite).
    double uniform() { return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-53; }

private:
    std::uint64_t key_;
    std::uint64_t counter_ = 0;
};

}  // namespace ltm::acquire
