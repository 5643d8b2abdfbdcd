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

namespace {
constexpr std::size_t kSmall = std::size_t(256) << 10;  // below this, malloc's own placement (io/Pages.h)
std::size_t whole_huge_pages(std::size_t bytes) { return (bytes + kHugePageBytes - 1) & ~(kHugePageBytes - 1); }
}  // namespace

void* allocate_pages(std::size_t bytes) {
    if (bytes < kSmall) {
        void* p = std::malloc(bytes > 0 ? bytes : 1);
        if (!p) throw std::bad_alloc();
        return p;
    }
    if (bytes > static_cast<std::size_t>(-1) / 2) throw std::bad_alloc();
    const std::size_t size = whole_huge_pages(bytes);
#if defined(__linux__)
    // One huge page more than needed, then the parts before and after the aligned run unmapped.
    const std::size_t over = size + kHugePageBytes;
    void* m = ::mmap(nullptr, over, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED) throw std::bad_alloc();
    const auto a = reinterpret_cast<std::uintptr_t>(m);
    const std::uintptr_t first = (a + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
    if (first > a) ::munmap(m, first - a);
    if (a + over > first + size) ::munmap(reinterpret_cast<void*>(first + size), a + over - (first + size));
    void* p = reinterpret_cast<void*>(first);
    advise_huge_pages(p, size);
    return p;
#else
    void* p = std::aligned_alloc(kHugePageBytes, size);
    if (!p) throw std::bad_alloc();
    return p;
#endif
}

void free_pages(void* p, std::size_t bytes) noexcept {
    if (!p) return;
    if (bytes < kSmall) {
        std::free(p);
        return;
    }
#if defined(__linux__)
    ::munmap(p, whole_huge_pages(bytes));
#else
    std::free(p);
#endif
}

}  // namespace ltm::io
