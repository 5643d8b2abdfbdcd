#include "io/Pages.h"

#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace ltm::io {

void advise_huge_pages(const void* p, std::size_t bytes) noexcept {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    const auto start = reinterpret_cast<std::uintptr_t>(p);
    if (p == nullptr || bytes < kHugePageBytes || bytes > UINTPTR_MAX - start) return;
    const std::uintptr_t first = (start + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
    const std::uintptr_t end = (start + bytes) & ~(kHugePageBytes - 1);
    if (end <= first) return;
    // Advice only: EINVAL (a kernel without THP) or ENOMEM leaves the ordinary pages.
    (void)madvise(reinterpret_cast<void*>(first), end - first, MADV_HUGEPAGE);
#else
    (void)p;
    (void)bytes;
#endif
}

void* allocate_pages(std::size_t bytes) {
    constexpr std::size_t kSmall = std::size_t(1) << 20;  // below this, malloc's own placement
    if (bytes < kSmall) {
        void* p = std::malloc(bytes > 0 ? bytes : 1);
        if (!p) throw std::bad_alloc();
        return p;
    }
    if (bytes > static_cast<std::size_t>(-1) - kHugePageBytes) throw std::bad_alloc();
    const std::size_t rounded = (bytes + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
    void* p = std::aligned_alloc(kHugePageBytes, rounded);
    if (!p) throw std::bad_alloc();
    advise_huge_pages(p, rounded);
    return p;
}

}  // namespace ltm::io
