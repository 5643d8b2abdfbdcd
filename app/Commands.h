#pragma once
// Subcommands of the ltmsim executable. Each registers itself on the CLI11 app; the one that
// runs stores its exit status: 0 success, 2 bad input (nothing written), 1 internal error.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace ltm::app {

inline constexpr const char* kVersion = "0.1.0";

void add_mesh_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_trace_rays_command(CLI::App& app);
void add_validate_command(CLI::App& app);
void add_features_command(CLI::App& app);
void add_experiment_command(CLI::App& app);
void add_dataset_command(CLI::App& app);
void add_acquire_command(CLI::App& app);

int exit_status();
void set_exit_status(int status);

// Runs a subcommand in a TBB arena of `threads` threads (0: all cores), so that --threads bounds
// every stage of the command (features, reference, writing), not only its trace: the conventions'
// "Every command that computes takes --threads N". Its status becomes the exit status; an
// exception that escapes is an internal error (status 1) reported as "ltmsim NAME: what".
void run_guarded(const std::string& name, int threads, const std::function<int()>& body);

// Whether a command may write the files `paths` (empty entries skipped): true if none of them
// exists, or `overwrite` (the command's --overwrite) is set; otherwise prints "ltmsim COMMAND:
// PATH exists; pass --overwrite to replace it" for the first that exists and returns false (exit
// status 2, before anything is written).
bool outputs_may_be_written(const std::string& command, const std::vector<std::string>& paths, bool overwrite);

}  // namespace ltm::app
