// `ltmsim mesh SCENE -o FILE.{ply,obj,off}`: the object with its defects, for MeshLab and meshio
// (what each format carries: geometry/MeshExport.h); with TetGen-meshed index regions also
// FILE.vtu (the tetrahedra with n per vertex, for ParaView and meshio), and the regions'
// boundaries appended to the surface mesh. Like every command, it replaces no existing output
// without --overwrite.
#include <algorithm>
#include <array>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>

#include "app/Commands.h"
#include "app/SceneSetup.h"
#include "defects/SolidBuilder.h"
#include "geometry/MeshExport.h"
#include "geometry/VtuExport.h"
#include "io/Json.h"

namespace ltm::app {

namespace {

struct MeshArgs {
    std::string scene, output, stats;
    bool ascii = false, binary = false, verbose = false, overwrite = false;
    int threads = 0;
};

// `picture`: the mesh written to `file` in `format` (the solid's mesh with the regions'
// boundaries); `vtu`: the tetrahedra's file, "" when none was written.
io::Json stats_json(const Scene& scene, const Solid& solid, const TriMesh& picture, const std::string& file,
                    MeshFormat format, const std::string& vtu, const StageReport& report) {
    size_t tetrahedra = 0;
    for (const TetMesh& r : solid.regions) tetrahedra += r.num_tets();
    return {{"scene", scene.source},
            {"triangles", solid.mesh.num_triangles()},
            {"vertices", solid.mesh.num_vertices()},
            // The glass's volume: the closed mesh's signed volume, its cavities (inward) subtracting.
            {"volume_mm3", io::json_number(solid.mesh.signed_volume())},
            {"file",
             {{"path", file},
              {"format", to_string(format)},
              {"vertices", picture.num_vertices()},
              {"triangles", picture.num_triangles()},
              {"signed_volume_mm3", io::json_number(picture.signed_volume())}}},
            {"vtu", vtu.empty() ? io::Json(nullptr) : io::Json(vtu)},
            {"surfaces", solid.surfaces.size()},
            {"object_chord_error_mm", io::json_number(solid.object_chord_error)},
            {"max_defect_chord_error_mm", io::json_number(solid.max_defect_chord_error)},
            {"boolean_operations", solid.boolean_operations},
            {"enclosed_defects", solid.enclosed_defects},
            {"tetrahedra", tetrahedra},
            {"stages", report.to_json()}};
}

// The boundary faces of a tetrahedral mesh (faces without a neighbour), wound outward.
TriMesh region_boundary(const TetMesh& m, int tag) {
    TriMesh out;
    std::vector<std::uint32_t> id(m.vertices.size(), UINT32_MAX);
    auto vertex = [&](std::uint32_t v) {
        if (id[v] == UINT32_MAX) id[v] = out.add_vertex(m.vertices[v]);
        return id[v];
    };
    for (size_t t = 0; t < m.tets.size(); ++t)
        for (int i = 0; i < 4; ++i) {
            if (m.neighbors[t][static_cast<size_t>(i)] >= 0) continue;
            std::array<std::uint32_t, 3> f{};
            for (int j = 0, k = 0; j < 4; ++j)
                if (j != i) f[static_cast<size_t>(k++)] = m.tets[t][static_cast<size_t>(j)];
            const Vec3& a = m.vertices[f[0]];
            const Vec3 n = cross(m.vertices[f[1]] - a, m.vertices[f[2]] - a);
            if (dot(n, m.vertices[m.tets[t][static_cast<size_t>(i)]] - a) > 0) std::swap(f[1], f[2]);
            out.add_triangle(vertex(f[0]), vertex(f[1]), vertex(f[2]), tag);
        }
    return out;
}

// All regions in one mesh (their vertices and tetrahedra renumbered one after the other).
TetMesh merged(const std::vector<TetMesh>& regions) {
    TetMesh all;
    for (const TetMesh& r : regions) {
        const auto base = static_cast<std::uint32_t>(all.vertices.size());
        const auto tbase = static_cast<std::int32_t>(all.tets.size());
        all.vertices.insert(all.vertices.end(), r.vertices.begin(), r.vertices.end());
        all.n2.insert(all.n2.end(), r.n2.begin(), r.n2.end());
        for (size_t t = 0; t < r.tets.size(); ++t) {
            auto v = r.tets[t];
            for (auto& x : v) x += base;
            all.tets.push_back(v);
            auto nb = r.neighbors[t];
            for (auto& x : nb)
                if (x >= 0) x += tbase;
            all.neighbors.push_back(nb);
        }
        all.error_bound = std::max(all.error_bound, r.error_bound);
    }
    all.name = "regions";
    return all;
}

int run(const MeshArgs& a) {
    // Bad output paths are caught before any work is done.
    MeshFormat format;
    try {
        format = mesh_format_for(a.output, a.binary);
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
    if (!outputs_may_be_written("mesh", {a.output, a.stats}, a.overwrite)) return 2;
    StageReport report;
    int status = 0;
    auto loaded = load_scene_and_solid(a.scene, report, status);
    if (!loaded) return status;
    const Scene& scene = loaded->scene;
    const Solid& solid = loaded->solid;
    // FILE.vtu is written only for a scene with meshed index regions, which only the solid tells.
    const std::string vtu =
        solid.regions.empty() ? std::string() : std::filesystem::path(a.output).replace_extension(".vtu").string();
    if (!outputs_may_be_written("mesh", {vtu}, a.overwrite)) return 2;
    TriMesh picture;
    {
        StageTimer t(&report, "write");
        // The smooth inhomogeneities' regions as their own components, tagged with their surface
        // (a picture of where the field is meshed; the whole-object region is the object itself).
        picture = solid.mesh;
        for (size_t i = 0; i < solid.regions.size(); ++i) {
            const int k = solid.region_defect[i];
            if (k < 0) continue;
            for (size_t tag = 0; tag < solid.surfaces.size(); ++tag)
                if (solid.surfaces[static_cast<int>(tag)].defect == k)
                    picture.append(region_boundary(solid.regions[i], static_cast<int>(tag)));
        }
        write_mesh(a.output, picture, solid.surfaces, format);
        if (!vtu.empty()) {
            write_vtu(vtu, merged(solid.regions));
            t.done(a.output + ", " + vtu);
        } else {
            t.done(a.output);
        }
    }
    if (!a.stats.empty())
        io::write_json_file(a.stats, stats_json(scene, solid, picture, a.output, format, vtu, report),
                            "mesh statistics");
    if (a.verbose) {
        std::cerr << fmt::format("ltmsim mesh {} -> {}\n", a.scene, a.output) << verbose_stages(report);
    }
    return 0;
}

}  // namespace

void add_mesh_command(CLI::App& app) {
    auto args = std::make_shared<MeshArgs>();
    CLI::App* cmd = app.add_subcommand("mesh", "Write the object with its defects as a mesh (PLY, OBJ or OFF)");
    cmd->add_option("scene", args->scene, "Scene file (YAML)")->required();
    cmd->add_option("-o,--output", args->output,
                    "Output mesh: .ply (ASCII with face colours and tags unless --binary), .obj or .off (geometry only)")
        ->required();
    CLI::Option* ascii = cmd->add_flag("--ascii", args->ascii, "ASCII PLY, the default: geometry, face colours by role, tags");
    cmd->add_flag("--binary", args->binary, "Binary PLY (float64): geometry only, no colours or tags")->excludes(ascii);
    cmd->add_flag("--overwrite", args->overwrite, "Replace existing output files (the mesh, FILE.vtu, --stats)");
    cmd->add_option("--stats", args->stats, "Also write, as JSON to this file, the written file's counts and volume and the stage times and sizes");
    cmd->add_flag("-v,--verbose", args->verbose, "Print the stages that ran, with times and sizes");
    add_threads_option(cmd, args->threads, "Threads (meshing is sequential; accepted for uniformity)");
    cmd->callback([args] { run_guarded("mesh", args->threads, [&] { return run(*args); }); });
}

}  // namespace ltm::app
