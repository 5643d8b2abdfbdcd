// io/PeakRss.h: each meter sees the peak of its own stretch, not the process's monotone maximum.
#include <gtest/gtest.h>

#include <sys/mman.h>

#include <cstring>

#include "io/PeakRss.h"
#include "tests/Tolerances.h"

using ltm::io::PeakRssMeter;

namespace {

// Maps, writes (so every page is resident) and unmaps `bytes`: RSS rises by `bytes`, then falls
// back (munmap returns the pages at once, unlike free() of a small block).
void touch_and_release(std::size_t bytes) {
    void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    ASSERT_NE(p, MAP_FAILED);
    std::memset(p, 1, bytes);
    ::munmap(p, bytes);
}

constexpr std::size_t kMiB = 1024 * 1024;

}  // namespace

TEST(PeakRss, EachMeterMeasuresItsOwnStretch) {
    const PeakRssMeter big;
    if (!big.per_run()) GTEST_SKIP() << "no per-run peak on this system: " << big.method();
    EXPECT_EQ(big.method(), "VmHWM after clear_refs");
    touch_and_release(64 * kMiB);
    // The 64 MiB were resident at once, and are gone again.
    EXPECT_GE(static_cast<double>(big.growth_bytes()), 64.0 * kMiB - ltm::tol::kRssNoiseBytes);
    const double big_peak = static_cast<double>(big.peak_bytes());  // before the next meter resets it
    EXPECT_LT(static_cast<double>(ltm::io::current_rss_bytes()),
              static_cast<double>(big.start_bytes()) + ltm::tol::kRssNoiseBytes);

    // A later, smaller stretch: its peak is its own 8 MiB, not the 64 MiB before it (getrusage's
    // ru_maxrss would still report those).
    const PeakRssMeter small;
    touch_and_release(8 * kMiB);
    EXPECT_GE(static_cast<double>(small.growth_bytes()), 8.0 * kMiB - ltm::tol::kRssNoiseBytes);
    EXPECT_LT(static_cast<double>(small.growth_bytes()), 8.0 * kMiB + ltm::tol::kRssNoiseBytes);
    EXPECT_LT(static_cast<double>(small.peak_bytes()), big_peak - 32.0 * kMiB);
}
