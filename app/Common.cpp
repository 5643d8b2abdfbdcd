#include <iostream>

#include "app/Commands.h"

namespace ltm::app {

namespace {
int g_status = 0;
}

int exit_status() { return g_status; }
void set_exit_status(int status) { g_status = status; }

void run_guarded(const std::string& name, const std::function<int()>& body) {
    try {
        set_exit_status(body());
    } catch (const std::exception& e) {
        std::cerr << "ltmsim " << name << ": " << e.what() << "\n";
        set_exit_status(1);
    }
}

}  // namespace ltm::app
