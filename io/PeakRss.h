#pragma once
// The peak resident memory (RSS) of one stretch of a process's life: one render, one benchmark
// row. Used by the benchmarks (bench/bench_scale.cpp) and by `ltmsim render` (run.json "memory").
//
// Why not getrusage: ru_maxrss is the process's high-water mark since it started, so it only ever
// grows; in a benchmark that runs small cases after a large one every later row reports the large
// one's peak. Linux lets a process reset its own high-water mark: writing "5" to
// /proc/self/clear_refs sets VmHWM (in /proc/self/status) to the current VmRSS (Linux >= 4.0).
// So a meter resets it when it starts and reads VmHWM when asked: the largest RSS since the start,
// which includes what the process already held then (`start_bytes`). `growth_bytes()` is the peak
// minus that: the memory the stretch itself added at its worst moment.
//
// Fallback, said out loud: where the reset is not possible (not Linux, /proc not mounted, or
// clear_refs not writable), `per_run()` is false, `method()` says "process-wide ru_maxrss (...)",
// and the peak is getrusage's, which is the peak of this stretch only when the stretch is the
// largest the process has run so far. Readers of the figures must then treat them as upper bounds.
//
// Resetting the high-water mark is process-wide: two meters alive at once (nested or in threads)
// see each other's resets; the later one wins. Use one at a time.
#include <cstdint>
#include <string>

namespace ltm::io {

// The process's current resident set (VmRSS), bytes; 0 where /proc/self/status cannot be read.
std::uint64_t current_rss_bytes();

class PeakRssMeter {
public:
    // Resets the high-water mark (or notes that it cannot) and records the current RSS.
    PeakRssMeter();

    // Largest RSS since construction (bytes): VmHWM after the reset, or ru_maxrss (see above).
    std::uint64_t peak_bytes() const;
    // RSS at construction.
    std::uint64_t start_bytes() const { return start_; }
    // peak_bytes() - start_bytes(), 0 if negative (pages freed before the peak was reached).
    std::uint64_t growth_bytes() const;

    // Whether the peak is this stretch's own (the reset worked).
    bool per_run() const { return per_run_; }
    // "VmHWM after clear_refs" or "process-wide ru_maxrss (<why the reset failed>)".
    const std::string& method() const { return method_; }

private:
    std::uint64_t start_ = 0;
    bool per_run_ = false;
    std::string method_;
};

}  // namespace ltm::io
