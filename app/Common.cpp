#include <tbb/task_arena.h>

#include <iostream>

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

}  // namespace ltm::app
