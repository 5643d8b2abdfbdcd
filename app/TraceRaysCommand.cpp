// `ltmsim trace-rays SCENE --rays FILE.jsonl`: the deterministic principal path of given rays
// (docs/conventions.md): transmitted at every interface, reflected only under total internal
// reflection. One JSON object per output line, in input order, on standard output.
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <iostream>
#include <tbb/parallel_for.h>

#include "app/Commands.h"
#include "app/SceneSetup.h"
#include "io/InputError.h"
#include "io/Json.h"
#include "trace/RaysFile.h"
#include "trace/Tracer.h"

namespace ltm::app {

namespace {

struct TraceRaysArgs {
    std::string scene, rays, representation = "auto";
    int threads = 0;
};

io::Json vec3(const Vec3& v) { return {io::json_number(v.x), io::json_number(v.y), io::json_number(v.z)}; }

int run(const TraceRaysArgs& a) {
    std::vector<InputRay> rays;
    try {
        rays = read_rays(a.rays);
    } catch (const InputError& e) {
        std::cerr << e.what() << "\n";
        return 2;
    }
    StageReport report;
    int status = 0;
    // auto and analytic trace closed forms where no defect cuts the glass: no mesh is built then.
    auto loaded = load_scene_and_solid(a.scene, report, status, representation_uses_surfaces_only(a.representation));
    if (!loaded) return status;
    const std::optional<Representation> chosen = resolve_representation("trace-rays", a.representation, *loaded);
    if (!chosen) return 2;
    TracerOptions topt;
    topt.representation = *chosen;
    const Tracer tracer(loaded->scene, loaded->solid, topt);
    // Each ray's line is computed on its own (principal paths draw no random numbers) and the
    // lines are written in input order, so the output does not depend on --threads.
    std::vector<std::string> lines(rays.size());
    auto trace_one = [&](size_t i) {
        const PrincipalPath p = tracer.principal_path(rays[i].origin, rays[i].direction);
        io::Json vertices = io::Json::array(), surfaces = io::Json::array();
        for (size_t j = 0; j < p.vertices.size(); ++j) {
            vertices.push_back(vec3(p.vertices[j]));
            surfaces.push_back(loaded->solid.surfaces[p.tags[j]].name);
        }
        io::Json line = {{"vertices", vertices},
                         {"surfaces", surfaces},
                         {"direction", vec3(p.direction)},
                         {"display_hit", p.display_hit ? io::Json{io::json_number(p.x), io::json_number(p.y)} : io::Json()},
                         {"display_pixel", p.display_hit ? io::Json{p.p, p.q} : io::Json()}};
        lines[i] = line.dump() + "\n";
    };
    tbb::parallel_for(size_t(0), rays.size(), trace_one);  // in run_guarded's arena of --threads
    std::string out;
    for (const auto& l : lines) out += l;
    std::cout << out << std::flush;
    return 0;
}

}  // namespace

void add_trace_rays_command(CLI::App& app) {
    auto args = std::make_shared<TraceRaysArgs>();
    CLI::App* cmd = app.add_subcommand("trace-rays", "Trace given rays' principal paths (JSON lines in, JSON lines out)");
    cmd->add_option("scene", args->scene, "Scene file (YAML)")->required();
    cmd->add_option("--rays", args->rays, "Rays: one {\"origin\": [x,y,z], \"direction\": [dx,dy,dz]} per line")->required();
    add_threads_option(cmd, args->threads, "Threads (default: all cores); the output is in input order whatever the number");
    add_representation_option(cmd, args->representation, {"auto", "refined", "analytic", "mesh-only"});
    cmd->callback([args] { run_guarded("trace-rays", args->threads, [&] { return run(*args); }); });
}

}  // namespace ltm::app
