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

// A check for an integer option, stated in words: "--threads: expected a whole number >= 1, or 0
// for all cores; got '-1'". CLI11's own checks do not serve: NonNegativeNumber prints its bound,
// the largest double, in 309 digits, and a double range lets 1.5 or 1e10 through to a conversion
// that fails with "Could not convert". The value must be decimal digits with an optional sign, in
// [min, max]; `zero_means` (with min = 0) names what 0 stands for ("all cores").
CLI::Validator whole_number(int min, int max, const std::string& zero_means = "");
// A non-negative int option's largest value.
inline constexpr int kMaxInt = 2147483647;

// --threads N, the same for every command that computes (0, the default: all cores).
void add_threads_option(CLI::App* cmd, int& threads, const std::string& help);

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
