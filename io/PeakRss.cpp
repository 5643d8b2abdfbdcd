#include "io/PeakRss.h"

#include <sys/resource.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace ltm::io {

namespace {

// The value of "<key>:   123 kB" in /proc/self/status, in bytes; -1 when missing.
long long status_kib(const char* key) {
    std::ifstream in("/proc/self/status");
    std::string line;
    const std::size_t n = std::strlen(key);
    while (std::getline(in, line))
        if (line.compare(0, n, key) == 0 && line.size() > n && line[n] == ':') {
            long long kib = -1;
            if (std::sscanf(line.c_str() + n + 1, "%lld", &kib) == 1) return kib;
        }
    return -1;
}

}  // namespace

std::uint64_t current_rss_bytes() {
    const long long kib = status_kib("VmRSS");
    return kib < 0 ? 0 : static_cast<std::uint64_t>(kib) * 1024;
}

PeakRssMeter::PeakRssMeter() {
    // "5" resets the peak RSS (VmHWM) to the current RSS: Documentation/filesystems/proc.rst.
    std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
    std::string why;
    if (!f) {
        why = std::string("cannot open /proc/self/clear_refs: ") + std::strerror(errno);
    } else {
        const bool wrote = std::fputs("5", f) >= 0;
        const bool closed = std::fclose(f) == 0;  // the write happens at the flush
        if (!wrote || !closed) why = std::string("cannot write /proc/self/clear_refs: ") + std::strerror(errno);
    }
    if (why.empty() && status_kib("VmHWM") < 0) why = "/proc/self/status has no VmHWM";
    per_run_ = why.empty();
    method_ = per_run_ ? "VmHWM after clear_refs" : "process-wide ru_maxrss (" + why + ")";
    start_ = current_rss_bytes();
}

std::uint64_t PeakRssMeter::peak_bytes() const {
    if (per_run_) {
        const long long kib = status_kib("VmHWM");
        if (kib >= 0) return static_cast<std::uint64_t>(kib) * 1024;
    }
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return static_cast<std::uint64_t>(ru.ru_maxrss) * 1024;  // kilobytes on Linux
}

std::uint64_t PeakRssMeter::growth_bytes() const {
    const std::uint64_t p = peak_bytes();
    return p > start_ ? p - start_ : 0;
}

}  // namespace ltm::io
