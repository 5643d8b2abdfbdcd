#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <charconv>
#include <filesystem>
#include <iostream>

#include "app/Commands.h"

namespace ltm::app {

namespace {
int g_status = 0;
}

CLI::Validator whole_number(int min, int max, const std::string& zero_means) {
    std::string words, desc;
    if (!zero_means.empty() && min == 0)
        words = fmt::format("a whole number >= 1, or 0 for {}", zero_means);
    else if (max == kMaxInt)
        words = fmt::format("a whole number >= {}", min);
    else
        words = fmt::format("a whole number from {} to {}", min, max);
    if (max == kMaxInt)
        desc = min == 0 ? "NONNEGATIVE" : min == 1 ? "POSITIVE" : fmt::format(">= {}", min);
    else
        desc = fmt::format("in [{} - {}]", min, max);
    return CLI::Validator(
        [min, max, words](std::string& input) -> std::string {
            // from_chars takes no '+'; one is allowed before the digits, as a sign.
            const bool plus = input.size() > 1 && input[0] == '+' && input[1] != '-';
            const char* first = input.data() + (plus ? 1 : 0);
            const char* last = input.data() + input.size();
            long long v = 0;
            const auto [end, ec] = std::from_chars(first, last, v);
            if (ec == std::errc() && end == last && v >= min && v <= max) return {};
            return fmt::format("expected {}; got '{}'", words, input);
        },
        desc);
}

void add_threads_option(CLI::App* cmd, int& threads, const std::string& help) {
    cmd->add_option("--threads", threads, help)->check(whole_number(0, kMaxInt, "all cores"));
}

int exit_status() { return g_status; }
void set_exit_status(int status) { g_status = status; }

void run_guarded(const std::string& name, int threads, const std::function<int()>& body) {
    try {
        tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
        set_exit_status(arena.execute(body));
    } catch (const std::exception& e) {
        std::cerr << "ltmsim " << name << ": " << e.what() << "\n";
        set_exit_status(1);
    }
}

bool outputs_may_be_written(const std::string& command, const std::vector<std::string>& paths, bool overwrite) {
    if (overwrite) return true;
    for (const std::string& p : paths) {
        std::error_code ec;
        if (p.empty() || !std::filesystem::exists(p, ec)) continue;
        std::cerr << fmt::format("ltmsim {}: {} exists; pass --overwrite to replace it\n", command, p);
        return false;
    }
    return true;
}

}  // namespace ltm::app
