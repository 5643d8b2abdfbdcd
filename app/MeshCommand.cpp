// `ltmsim mesh SCENE -o FILE.{ply,obj,off}`: the object with its defects, for MeshLab.
#include <filesystem>
#include <fmt/format.h>
#include <iostream>

#include "app/Commands.h"
#include "app/SceneSetup.h"
#include "defects/SolidBuilder.h"
#include "geometry/MeshExport.h"

namespace ltm::app {

namespace {

struct MeshArgs {
    std::string scene, output, stats;
    bool ascii = false, verbose = false;
    int threads = 0;
};

std::string stats_json(const Scene& scene, const Solid& solid, const StageReport& report) {
    return fmt::format(
        "{{\n  \"scene\": \"{}\",\n  \"triangles\": {},\n  \"vertices\": {},\n  \"surfaces\": {},\n"
        "  \"object_chord_error_mm\": {:.6g},\n  \"max_defect_chord_error_mm\": {:.6g},\n"
        "  \"boolean_operations\": {},\n  \"enclosed_defects\": {},\n  \"stages\": {}\n}}\n",
        scene.source, solid.mesh.num_triangles(), solid.mesh.num_vertices(), solid.surfaces.size(),
        solid.object_chord_error, solid.max_defect_chord_error, solid.boolean_operations, solid.enclosed_defects,
        report.to_json());
}

int run(const MeshArgs& a) {
    // Bad output paths are caught before any work is done.
    MeshFormat format;
    try {
        format = mesh_format_for(a.output, a.ascii);
    } catch (const std::exception& e) {
        std::cerr << "ltmsim mesh: " << e.what() << "\n";
        return 2;
    }
    for (const std::string& out : {a.output, a.stats}) {
        if (out.empty()) continue;
        const std::filesystem::path p(out);
        const auto folder = p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
        if (!std::filesystem::is_directory(folder)) {
            std::cerr << fmt::format("ltmsim mesh: cannot write {}: folder {} does not exist\n", out, folder.string());
            return 2;
        }
    }
    StageReport report;
    int status = 0;
    auto loaded = load_scene_and_solid(a.scene, report, status);
    if (!loaded) return status;
    const Scene& scene = loaded->scene;
    const Solid& solid = loaded->solid;
    {
        StageTimer t(&report, "write");
        write_mesh(a.output, solid.mesh, solid.surfaces, format);
        t.done(a.output);
    }
    if (!a.stats.empty()) write_text_atomically(a.stats, stats_json(scene, solid, report));
    if (a.verbose) {
        std::cerr << fmt::format("ltmsim mesh {} -> {}\n", a.scene, a.output) << report.to_text();
        if (!report.ran("boolean")) std::cerr << "  (no Boolean ran)\n";
    }
    return 0;
}

}  // namespace

void add_mesh_command(CLI::App& app) {
    auto args = std::make_shared<MeshArgs>();
    CLI::App* cmd = app.add_subcommand("mesh", "Write the object with its defects as a mesh (PLY, OBJ or OFF)");
    cmd->add_option("scene", args->scene, "Scene file (YAML)")->required();
    cmd->add_option("-o,--output", args->output, "Output mesh: .ply (binary unless --ascii), .obj or .off")->required();
    cmd->add_flag("--ascii", args->ascii, "Write ASCII PLY");
    cmd->add_option("--stats", args->stats, "Also write stage times and sizes as JSON to this file");
    cmd->add_flag("-v,--verbose", args->verbose, "Print the stages that ran, with times and sizes");
    cmd->add_option("--threads", args->threads, "Threads (meshing is sequential; accepted for uniformity)")
        ->check(CLI::NonNegativeNumber);
    cmd->callback([args] { run_guarded("mesh", [&] { return run(*args); }); });
}

}  // namespace ltm::app
