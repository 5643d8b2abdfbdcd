#pragma once
// Large buffers in transparent huge pages.
//
// Why: every fresh 4 KiB page a process touches first costs a page fault and the kernel's
// clearing of it. On the virtual machines ltmsim is measured on that is 9-12 us a page, so the
// arrays a render fills for the first time (T's entries, the 14 feature channels, a preview's
// picture) spent more time faulting than being written (docs/benchmarks.md). A 2 MiB transparent
// huge page is faulted once for 512 small ones: 0.25 us per 4 KiB measured here. Linux gives huge
// pages to anonymous memory only where asked (`madvise(MADV_HUGEPAGE)`) when the system's mode is
// `madvise`, Debian's default, and to every large mapping in mode `always`; in mode `never` the
// advice is ignored.
//
// The advice changes speed and the granularity of memory, never contents: a huge page is cleared
// as the small ones are, and a failed or refused madvise leaves ordinary pages. The cost is
// resident memory rounded up to 2 MiB where a buffer's pages are touched: at most 2 MiB per
// advised buffer beyond what it uses.
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

namespace ltm::io {

// The size of a transparent huge page on x86-64 and (with 4 KiB base pages) arm64 Linux.
inline constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;

// Asks for huge pages on the whole 2 MiB pages inside [p, p + bytes): an allocation's head and
// tail that do not fill one stay in small pages. Does nothing for fewer bytes than one huge page
// holds, or where the system has no such advice. Never fails: it is advice.
void advise_huge_pages(const void* p, std::size_t bytes) noexcept;

// v.reserve(n), then the advice on the reserved bytes: for a large array that is filled after this
// (resize, push_back), so that its pages are faulted in huge. Whole huge pages lie inside any
// reservation of 4 MiB or more; one of 2-4 MiB may hold none (a vector's storage is not aligned).
template <class T>
void reserve_in_huge_pages(std::vector<T>& v, std::size_t n) {
    v.reserve(n);
    advise_huge_pages(v.data(), v.capacity() * sizeof(T));
}

// Uninitialised storage of at least `bytes` bytes: from 1 MiB up, aligned to and rounded up to
// whole huge pages and advised to take them, so that all of it is faulted in huge. Throws
// std::bad_alloc. Free it with std::free (PagesDeleter).
void* allocate_pages(std::size_t bytes);

struct PagesDeleter {
    void operator()(void* p) const noexcept { std::free(p); }
};

// Room a thread keeps for scratch objects it fully writes before it reads them (the pictures and
// blocks io/ encodes, a preview's surface): grown (with an eighth more, for the next slightly
// larger picture) by a fresh, uncleared allocation (allocate_pages) that replaces the old one, so
// that no page is copied or cleared, and only the pages written are faulted in.
template <class T>
class Scratch {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>,
                  "Scratch holds plain values that need no construction");

public:
    // At least n objects' room; what the room held before is gone.
    T* get(std::size_t n) {
        if (n > capacity_) {
            data_.reset();  // the old objects go first: they are not needed, and not copied
            capacity_ = 0;  // so that a failed allocation below leaves an empty buffer, not a dangling size
            constexpr std::size_t most = static_cast<std::size_t>(-1) / sizeof(T);
            if (n > most) throw std::bad_alloc();
            const std::size_t grown = n <= most - n / 8 ? n + n / 8 : n;
            // Storage from the allocator has no objects yet; T is an implicit-lifetime type, so
            // writing it there begins its objects' lifetime (C++20 [intro.object]).
            data_.reset(static_cast<T*>(allocate_pages(grown * sizeof(T))));
            capacity_ = grown;
        }
        return data_.get();
    }
    std::size_t capacity() const { return capacity_; }

private:
    std::unique_ptr<T, PagesDeleter> data_;
    std::size_t capacity_ = 0;
};

using ScratchBytes = Scratch<unsigned char>;

}  // namespace ltm::io
