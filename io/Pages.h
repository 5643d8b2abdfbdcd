#pragma once
// Large buffers in transparent huge pages.
//
// Why: every fresh 4 KiB page a process touches first costs a page fault and the kernel's
// clearing of it. On the virtual machines ltmsim is measured on that is 9-12 us a page, so the
// arrays a render fills for the first time (T's entries, the 14 feature channels, a preview's
// picture) would spend more time faulting than being written (docs/benchmarks.md). A 2 MiB transparent
// huge page is faulted once for 512 small ones: 0.25 us per 4 KiB measured here. Linux gives huge
// pages to anonymous memory only where asked (`madvise(MADV_HUGEPAGE)`) when the system's mode is
// `madvise`, Debian's default, and to every large mapping in mode `always`; in mode `never` the
// advice is ignored.
//
// The advice changes speed and the granularity of memory, never contents: a huge page is cleared
// as the small ones are, and a failed or refused madvise leaves ordinary pages. The cost is
// resident memory rounded up to 2 MiB where a buffer's pages are touched: at most 2 MiB per
// advised buffer beyond what it uses (for the scratch buffers, per thread that keeps one).
//
// The advice is given only on memory that goes back to the system when it is freed, so that it
// never outlives its buffer: on this module's own mappings (allocate_pages) and on vector
// reservations large enough that the C library always maps them apart (kAlwaysMapped). Advice on
// heap memory would stay there after the free, on whatever small allocations later reuse it.
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace ltm::io {

// The size of a transparent huge page on x86-64 and (with 4 KiB base pages) arm64 Linux.
inline constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;

// Asks for huge pages on the whole 2 MiB pages inside [p, p + bytes): an allocation's head and
// tail that do not fill one stay in small pages. Does nothing for fewer bytes than one huge page
// holds, or where the system has no such advice. Never fails: it is advice.
void advise_huge_pages(const void* p, std::size_t bytes) noexcept;

// From this size on, glibc's malloc always serves an allocation by its own mmap and returns it
// by munmap on free (its dynamic mmap threshold never rises above DEFAULT_MMAP_THRESHOLD_MAX,
// 32 MiB on 64-bit systems), so advice given on it ends with it.
inline constexpr std::size_t kAlwaysMapped = std::size_t(32) << 20;

// v.reserve(n), then, for a reservation of kAlwaysMapped bytes or more, the advice on it: for a
// large array that is filled after this (resize, push_back), so that its pages are faulted in
// huge (T's entries in a large render). A vector's storage is not aligned: its head and tail
// short of a whole huge page stay in small pages.
template <class T>
void reserve_in_huge_pages(std::vector<T>& v, std::size_t n) {
    v.reserve(n);
    if (v.capacity() >= kAlwaysMapped / sizeof(T)) advise_huge_pages(v.data(), v.capacity() * sizeof(T));
}

// Uninitialised storage of at least `bytes` bytes: from 256 KiB up, a mapping of its own, aligned
// to and rounded up to whole huge pages and advised to take them, so that all of it is faulted in
// huge; below, malloc's. Throws std::bad_alloc. Give it back with free_pages and the same size.
// (256 KiB: igzip's working memory, 324 KB at level 2, and a default-scene preview's rows, 0.8 MB,
// are kept by each writing thread; in small pages their first use faulted 80 and 200 pages, a few
// milliseconds of each render's write stage. A kept buffer costs at most 2 MiB of memory.)
void* allocate_pages(std::size_t bytes);
void free_pages(void* p, std::size_t bytes) noexcept;

// Room a thread keeps for scratch objects it fully writes before it reads them (the pictures and
// blocks io/ encodes, a preview's surface): grown (with an eighth more, for the next slightly
// larger picture) by a fresh, uncleared allocation (allocate_pages) that replaces the old one, so
// that no page is copied or cleared, and only the pages written are faulted in.
template <class T>
class Scratch {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>,
                  "Scratch holds plain values that need no construction");
    static_assert(alignof(T) <= alignof(std::max_align_t), "malloc's alignment serves small requests");

public:
    Scratch() = default;
    ~Scratch() { release(); }
    Scratch(const Scratch&) = delete;
    Scratch& operator=(const Scratch&) = delete;

    // At least n objects' room; what the room held before is gone.
    T* get(std::size_t n) {
        if (n > capacity_) {
            release();  // the old objects go first: they are not needed, and not copied
            constexpr std::size_t most = static_cast<std::size_t>(-1) / sizeof(T);
            if (n > most) throw std::bad_alloc();
            const std::size_t grown = n <= most - n / 8 ? n + n / 8 : n;
            // Fresh storage from the system holds no objects yet; T is trivial, and writing it
            // there makes its values (as for malloc'ed memory).
            data_ = static_cast<T*>(allocate_pages(grown * sizeof(T)));
            capacity_ = grown;
        }
        return data_;
    }
    std::size_t capacity() const { return capacity_; }
    // Exchanges the two rooms (a buffer lent to an object and given back).
    void swap(Scratch& other) noexcept {
        std::swap(data_, other.data_);
        std::swap(capacity_, other.capacity_);
    }

private:
    void release() noexcept {
        if (data_) free_pages(data_, capacity_ * sizeof(T));
        data_ = nullptr;  // a failed allocation after this leaves an empty buffer, not a dangling size
        capacity_ = 0;
    }
    T* data_ = nullptr;
    std::size_t capacity_ = 0;
};

using ScratchBytes = Scratch<unsigned char>;

}  // namespace ltm::io
