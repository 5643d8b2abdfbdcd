// io/Pages.h: huge-page advice lands on the whole 2 MiB pages of a buffer and nowhere else, never
// changes a byte, and the scratch storage is aligned, sized and replaced as documented.
//
// The kernel's verdict is read from /proc/self/smaps: each mapping's "THPeligible" line is 1 when
// the kernel may back it with transparent huge pages (recent kernels print it for every mapping).
// Whether it then finds free huge pages is the machine's state, not the contract: not asserted.
#include <gtest/gtest.h>

#include <sys/mman.h>
#include <sys/prctl.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "io/Pages.h"

using ltm::io::kHugePageBytes;

namespace {

// THPeligible of the mapping holding p, or nothing where smaps does not say.
std::optional<bool> thp_eligible(const void* p) {
    const auto a = reinterpret_cast<std::uintptr_t>(p);
    std::ifstream in("/proc/self/smaps");
    std::string line;
    bool inside = false;
    while (std::getline(in, line)) {
        std::uintptr_t lo = 0, hi = 0;
        char dash = 0;
        std::istringstream head(line);
        if (head >> std::hex >> lo >> dash >> hi && dash == '-' && line.find(':') > line.find(' ')) {
            inside = lo <= a && a < hi;  // a mapping's first line: "lo-hi perms offset dev inode path"
            continue;
        }
        if (inside && line.rfind("THPeligible:", 0) == 0) return line.find('1') != std::string::npos;
    }
    return std::nullopt;
}

// An anonymous mapping of `huge` huge pages, aligned to them (mapped with one more, then trimmed).
struct AlignedMapping {
    explicit AlignedMapping(std::size_t huge) : bytes(huge * kHugePageBytes) {
        const std::size_t over = bytes + kHugePageBytes;
        void* m = ::mmap(nullptr, over, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (m == MAP_FAILED) return;
        const auto a = reinterpret_cast<std::uintptr_t>(m);
        const std::uintptr_t first = (a + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
        if (first > a) ::munmap(m, first - a);
        if (a + over > first + bytes) ::munmap(reinterpret_cast<void*>(first + bytes), a + over - (first + bytes));
        p = reinterpret_cast<unsigned char*>(first);
    }
    ~AlignedMapping() {
        if (p) ::munmap(p, bytes);
    }
    std::size_t bytes;
    unsigned char* p = nullptr;
};

// The first word in brackets of a sysfs setting ("[madvise]"), empty if unreadable.
std::string bracketed(const std::string& file) {
    std::ifstream in(file);
    std::string line;
    if (!std::getline(in, line)) return {};
    const auto open = line.find('['), close = line.find(']');
    if (open == std::string::npos || close == std::string::npos || close < open) return {};
    return line.substr(open + 1, close - open - 1);
}

// The system's mode ("always", "madvise" or "never"); empty if unknown.
std::string thp_mode() { return bracketed("/sys/kernel/mm/transparent_hugepage/enabled"); }

// Whether the advice alone decides eligibility for 2 MiB pages here: the system's mode is
// "madvise" (in "always" every large mapping is eligible already, in "never" none is), the PMD
// huge page is 2 MiB (not arm64 with 64 KiB pages), no other huge page size is "always" and 2 MiB
// is not "never" (Linux >= 6.8's per-size settings, which THPeligible also reports), and the
// process has not had THP disabled (prctl PR_SET_THP_DISABLE, inherited from a wrapper).
bool advice_decides() {
    if (thp_mode() != "madvise") return false;
    std::ifstream pmd("/sys/kernel/mm/transparent_hugepage/hpage_pmd_size");
    std::size_t size = 0;
    if (pmd >> size && size != kHugePageBytes) return false;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator("/sys/kernel/mm/transparent_hugepage", ec)) {
        const std::string name = e.path().filename().string();
        if (name.rfind("hugepages-", 0) != 0) continue;
        const std::string mode = bracketed((e.path() / "enabled").string());
        if (mode == "always") return false;
        if (name == "hugepages-2048kB" && mode == "never") return false;
    }
    return ::prctl(PR_GET_THP_DISABLE, 0, 0, 0, 0) != 1;
}

}  // namespace

TEST(Pages, AdviceMakesTheWholeHugePagesInsideABufferEligibleAndNothingElse) {
    if (!advice_decides()) GTEST_SKIP() << "transparent huge pages are in mode '" << thp_mode() << "', not 'madvise'";
    AlignedMapping m(4);
    ASSERT_NE(m.p, nullptr);
    const auto before = thp_eligible(m.p + kHugePageBytes);
    if (!before) GTEST_SKIP() << "/proc/self/smaps has no THPeligible lines (Linux < 5.8)";
    EXPECT_FALSE(*before) << "an anonymous mapping is not eligible before the advice in 'madvise' mode";

    // A buffer from the middle of the first huge page to the middle of the fourth holds the
    // second and third whole: those are advised, the first and fourth are not.
    ltm::io::advise_huge_pages(m.p + kHugePageBytes / 2, 3 * kHugePageBytes);
    EXPECT_EQ(thp_eligible(m.p + kHugePageBytes), std::optional<bool>(true));
    EXPECT_EQ(thp_eligible(m.p + 2 * kHugePageBytes), std::optional<bool>(true));
    EXPECT_EQ(thp_eligible(m.p), std::optional<bool>(false));
    EXPECT_EQ(thp_eligible(m.p + 3 * kHugePageBytes), std::optional<bool>(false));
}

TEST(Pages, ABufferHoldingNoWholeHugePageIsNotAdvised) {
    if (!advice_decides()) GTEST_SKIP() << "transparent huge pages are in mode '" << thp_mode() << "', not 'madvise'";
    AlignedMapping m(2);
    ASSERT_NE(m.p, nullptr);
    if (!thp_eligible(m.p)) GTEST_SKIP() << "/proc/self/smaps has no THPeligible lines (Linux < 5.8)";
    // 2 MiB straddling the boundary between the two huge pages: neither lies inside it.
    ltm::io::advise_huge_pages(m.p + kHugePageBytes / 2, kHugePageBytes);
    EXPECT_EQ(thp_eligible(m.p), std::optional<bool>(false));
    EXPECT_EQ(thp_eligible(m.p + kHugePageBytes), std::optional<bool>(false));
    // Less than one huge page, or no buffer: nothing, and no failure.
    ltm::io::advise_huge_pages(m.p, kHugePageBytes - 1);
    EXPECT_EQ(thp_eligible(m.p), std::optional<bool>(false));
    ltm::io::advise_huge_pages(nullptr, 8 * kHugePageBytes);
}

TEST(Pages, AdviceNeverChangesABuffersBytes) {
    std::vector<std::uint32_t> v(3 * kHugePageBytes / 4 + 12345);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<std::uint32_t>(i * 2654435761u);
    const std::vector<std::uint32_t> copy = v;
    ltm::io::advise_huge_pages(v.data(), v.size() * sizeof(v[0]));
    EXPECT_EQ(v, copy);
    // reserve_in_huge_pages keeps what a vector holds, and its room is at least what was asked.
    std::vector<std::uint32_t> w = copy;
    ltm::io::reserve_in_huge_pages(w, 4 * copy.size());
    EXPECT_GE(w.capacity(), 4 * copy.size());
    EXPECT_EQ(w, copy);
}

// A vector reservation is advised from kAlwaysMapped bytes on (memory malloc always maps apart,
// so the advice ends with it), and not below (it may be heap memory that outlives the vector).
TEST(Pages, OnlyReservationsThatAreMappedApartAreAdvised) {
    if (!advice_decides()) GTEST_SKIP() << "the advice does not decide eligibility here (mode '" << thp_mode() << "')";
    std::vector<float> large;
    ltm::io::reserve_in_huge_pages(large, ltm::io::kAlwaysMapped / sizeof(float));
    const auto* middle = reinterpret_cast<const unsigned char*>(large.data()) + ltm::io::kAlwaysMapped / 2;
    const auto eligible = thp_eligible(middle);
    if (!eligible) GTEST_SKIP() << "/proc/self/smaps has no THPeligible lines (an older kernel)";
    EXPECT_TRUE(*eligible) << "a 32 MiB reservation's middle";
    std::vector<float> small;
    ltm::io::reserve_in_huge_pages(small, ltm::io::kAlwaysMapped / sizeof(float) / 2 - 4096);
    EXPECT_EQ(thp_eligible(reinterpret_cast<const unsigned char*>(small.data()) + ltm::io::kAlwaysMapped / 4),
              std::optional<bool>(false))
        << "a 16 MiB reservation";
}

TEST(Pages, LargeAllocationsAreWholeAdvisedHugePages) {
    const std::size_t bytes = 3 * kHugePageBytes + 1;  // rounded up to four huge pages
    void* p = ltm::io::allocate_pages(bytes);
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % kHugePageBytes, 0u);
    std::memset(p, 0x5a, 4 * kHugePageBytes);  // all four are the caller's to write
    if (advice_decides() && thp_eligible(p)) {
        for (int k = 0; k < 4; ++k)
            EXPECT_EQ(thp_eligible(static_cast<unsigned char*>(p) + k * kHugePageBytes), std::optional<bool>(true)) << k;
    }
    // The mapping is the allocation's own: freeing it unmaps it whole.
    ltm::io::free_pages(p, bytes);
    EXPECT_EQ(thp_eligible(p), std::nullopt) << "the pages are still mapped after free_pages";
    // From 256 KiB up a buffer is a mapping of its own, one whole huge page here (igzip's working
    // memory, 324 KB, and a preview's rows are kept per thread in such buffers).
    void* m = ltm::io::allocate_pages(256 << 10);
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(m) % kHugePageBytes, 0u);
    std::memset(m, 0x5a, kHugePageBytes);  // rounded up to the whole huge page, all of it writable
    ltm::io::free_pages(m, 256 << 10);
    EXPECT_EQ(thp_eligible(m), std::nullopt) << "the pages are still mapped after free_pages";
    // A small one is malloc's, writable for its size.
    void* q = ltm::io::allocate_pages(100);
    ASSERT_NE(q, nullptr);
    std::memset(q, 1, 100);
    ltm::io::free_pages(q, 100);
    void* z = ltm::io::allocate_pages(0);  // a zero-size request still gets a pointer to free
    ASSERT_NE(z, nullptr);
    ltm::io::free_pages(z, 0);
}

TEST(Pages, ScratchGrowsByAnEighthAndKeepsItsRoomForSmallerRequests) {
    ltm::io::Scratch<double> s;
    EXPECT_EQ(s.capacity(), 0u);
    double* a = s.get(800);
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(s.capacity(), 900u);  // 800 + 800 / 8
    a[899] = 1.0;                   // the whole room is writable
    EXPECT_EQ(s.get(900), a);       // within the room: the same storage
    EXPECT_EQ(s.get(10), a);
    double* b = s.get(901);  // beyond: fresh storage, 901 + 112
    ASSERT_NE(b, nullptr);
    EXPECT_EQ(s.capacity(), 1013u);
    b[1012] = 2.0;
    // A request whose bytes overflow size_t is refused, not wrapped around to a small buffer, and
    // the scratch is left empty.
    EXPECT_THROW(s.get(std::numeric_limits<std::size_t>::max() / 4), std::bad_alloc);
    EXPECT_EQ(s.capacity(), 0u);
    EXPECT_NE(s.get(5), nullptr);
}
