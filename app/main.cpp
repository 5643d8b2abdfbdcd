// The ltmsim command. Subcommands arrive with the issues that ask for them
// (docs/conventions.md, "Command line"): mesh, render, trace-rays, validate, features, experiment, dataset, acquire.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fmt/format.h>

#include "app/Commands.h"

int main(int argc, char** argv) {
    CLI::App app{"ltmsim: light transport matrices of transparent objects under inspection"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string(ltm::app::kVersion));
    ltm::app::add_mesh_command(app);
    ltm::app::add_render_command(app);
    ltm::app::add_trace_rays_command(app);
    ltm::app::add_validate_command(app);
    ltm::app::add_features_command(app);
    ltm::app::add_experiment_command(app);
    ltm::app::add_dataset_command(app);
    ltm::app::add_acquire_command(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // Usage errors are bad input: exit status 2 (CLI11's own codes are remapped).
        const int rc = app.exit(e);
        return rc == 0 ? 0 : 2;
    }
    return ltm::app::exit_status();
}
