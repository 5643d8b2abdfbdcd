#include <tbb/task_arena.h>

#include <filesystem>
#include <iostream>

#include <fmt/format.h>

#include "app/Commands.h"

namespace ltm::app {

namespace {
int g_status = 0;
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
