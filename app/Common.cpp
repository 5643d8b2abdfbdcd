#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <unistd.h>

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

void write_text_atomically(const std::string& path, const std::string& text) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(folder))
        throw std::runtime_error("cannot write " + path + ": folder " + folder.string() + " does not exist");
    const fs::path tmp = folder / ("." + target.filename().string() + ".tmp" + std::to_string(::getpid()));
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out << text;
        out.flush();
        if (!out) {
            std::error_code ec;
            fs::remove(tmp, ec);
            throw std::runtime_error("cannot write " + path);
        }
    }
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot write " + path + ": " + ec.message());
    }
}

}  // namespace ltm::app
