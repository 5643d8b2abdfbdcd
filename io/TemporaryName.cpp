#include "io/TemporaryName.h"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <random>

namespace ltm::io::detail {

namespace {

constexpr const char* kMark = ".tmp-";
constexpr std::size_t kHexDigits = 16;

bool all_of(const std::string& s, std::size_t from, std::size_t to, int (*pred)(int)) {
    if (from >= to) return false;
    for (std::size_t i = from; i < to; ++i)
        if (!pred(static_cast<unsigned char>(s[i]))) return false;
    return true;
}
int is_decimal(int c) { return c >= '0' && c <= '9'; }
int is_lower_hex(int c) { return is_decimal(c) || (c >= 'a' && c <= 'f'); }

}  // namespace

std::filesystem::path folder_of(const std::string& path) {
    std::filesystem::path folder = std::filesystem::path(path).parent_path();
    return folder.empty() ? std::filesystem::path(".") : folder;
}

std::string temporary_name(const std::string& name, bool with_pid) {
    std::random_device rd;
    const std::uint64_t r = (static_cast<std::uint64_t>(rd()) << 32) ^ rd();
    char suffix[64];
    if (with_pid)
        std::snprintf(suffix, sizeof suffix, "%s%ld-%016llx", kMark, static_cast<long>(::getpid()),
                      static_cast<unsigned long long>(r));
    else
        std::snprintf(suffix, sizeof suffix, "%s%016llx", kMark, static_cast<unsigned long long>(r));
    return "." + name + suffix;
}

bool is_temporary_name(const std::string& filename, bool with_pid) {
    // "." + a non-empty name + ".tmp-" + [pid "-"] + 16 hex digits
    const std::size_t mark = filename.rfind(kMark);
    if (filename.size() < 2 || filename[0] != '.' || mark == std::string::npos || mark < 2) return false;
    const std::size_t tail = mark + std::char_traits<char>::length(kMark);
    if (filename.size() < tail + kHexDigits) return false;
    const std::size_t hex = filename.size() - kHexDigits;
    if (!all_of(filename, hex, filename.size(), is_lower_hex)) return false;
    if (!with_pid) return hex == tail;
    return hex >= tail + 2 && filename[hex - 1] == '-' && all_of(filename, tail, hex - 1, is_decimal);
}

}  // namespace ltm::io::detail
