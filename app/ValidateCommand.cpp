// `ltmsim validate SCENE`: traced paths against analytic Snell's-law solutions. Prints the
// largest display-hit and direction errors per ray category, for the chosen representation and,
// beside it, for the mesh alone; exits 1 if a well-conditioned ray is off by more than its
// tolerance (validation/ValidationTolerance.h) or follows other surfaces.
#include <fmt/format.h>
#include <iostream>

#include "app/Commands.h"
#include "app/SceneSetup.h"
#include "validation/AnalyticScene.h"
#include "validation/Validate.h"

namespace ltm::app {

namespace {

struct ValidateArgs {
    std::string scene, representation = "refined";
    int density = 4, threads = 0;
};

int run(const ValidateArgs& a) {
    StageReport report;
    int status = 0;
    auto loaded = load_scene_and_solid(a.scene, report, status);
    if (!loaded) return status;
    std::string why;
    if (!validation::can_validate(loaded->scene, &why)) {
        std::cerr << fmt::format("ltmsim validate: {}: no analytic reference for this scene: {}\n", loaded->scene.source, why);
        return 2;
    }
    const std::optional<Representation> chosen = resolve_representation("validate", a.representation, *loaded);
    if (!chosen) return 2;
    const Representation rep = *chosen;
    const validation::ValidationReport main = validation::validate(loaded->scene, loaded->solid, rep, a.density);
    std::cout << validation::format_report(main, true);
    // The facets alone, for comparison (straight segments only: not for graded-index glass).
    if (loaded->solid.regions.empty() && !loaded->scene.object.index_field.graded()) {
        const validation::ValidationReport mesh =
            validation::validate(loaded->scene, loaded->solid, Representation::MeshOnly, a.density);
        std::cout << "\nfor comparison, without refinement:\n" << validation::format_report(mesh, false);
    }
    return main.passed() ? 0 : 1;
}

}  // namespace

void add_validate_command(CLI::App& app) {
    auto args = std::make_shared<ValidateArgs>();
    CLI::App* cmd = app.add_subcommand("validate", "Check traced paths against analytic Snell's-law solutions");
    cmd->add_option("scene", args->scene, "Scene file (YAML)")->required();
    cmd->add_option("--density", args->density, "Ray set density (1: ~200 rays)")->check(whole_number(1, kMaxInt));
    add_representation_option(cmd, args->representation, {"refined", "analytic"});
    add_threads_option(cmd, args->threads, "Threads (accepted for uniformity; rays are traced in order)");
    cmd->callback([args] { run_guarded("validate", args->threads, [&] { return run(*args); }); });
}

}  // namespace ltm::app
