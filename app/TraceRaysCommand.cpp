// `ltmsim trace-rays SCENE --rays FILE.jsonl`: the deterministic principal path of given rays
// (docs/conventions.md): transmitted at every interface, reflected only under total internal
// reflection. One JSON object per output line, in input order, on standard output.
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <iostream>

#include "app/Commands.h"
#include "app/JsonLine.h"
#include "app/SceneSetup.h"
#include "scene/SceneJson.h"
#include "trace/Tracer.h"

namespace ltm::app {

namespace {

struct TraceRaysArgs {
    std::string scene, rays, representation = "auto";
    int threads = 0;
};

struct InputRay {
    Vec3 origin, direction;
};

// Reads and checks every line before anything is traced: bad input prints FILE:LINE[:COL] and
// the problem, and nothing is written.
bool read_rays(const std::string& path, std::vector<InputRay>& out) {
    std::ifstream in(path);
    if (!in) {
        std::cerr << fmt::format("{}: cannot read rays file\n", path);
        return false;
    }
    std::string line;
    for (size_t n = 1; std::getline(in, line); ++n) {
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;  // blank lines are allowed
        auto bad = [&](const std::string& what) {
            std::cerr << fmt::format("{}:{}: {}\n", path, n, what);
            return false;
        };
        JsonValue v;
        try {
            v = parse_json_line(line);
        } catch (const JsonError& e) {
            std::cerr << fmt::format("{}:{}:{}: malformed JSON: {}\n", path, n, e.column, e.what());
            return false;
        }
        if (v.type != JsonValue::Type::Object) return bad("expected an object {\"origin\": [x, y, z], \"direction\": [dx, dy, dz]}");
        InputRay r;
        bool has_o = false, has_d = false;
        for (const auto& [key, val] : v.object) {
            if (key != "origin" && key != "direction")
                return bad(fmt::format("unknown key \"{}\" (expected \"origin\" and \"direction\")", key));
            if (val.type != JsonValue::Type::Array || val.array.size() != 3)
                return bad(fmt::format("\"{}\" must be a list of 3 numbers", key));
            Vec3 x;
            for (int i = 0; i < 3; ++i) {
                if (val.array[static_cast<size_t>(i)].type != JsonValue::Type::Number)
                    return bad(fmt::format("\"{}\" must be a list of 3 numbers", key));
                x[i] = val.array[static_cast<size_t>(i)].number;
            }
            if (!is_finite(x)) return bad(fmt::format("\"{}\" must be finite", key));
            (key == "origin" ? r.origin : r.direction) = x;
            (key == "origin" ? has_o : has_d) = true;
        }
        if (!has_o) return bad("missing key \"origin\"");
        if (!has_d) return bad("missing key \"direction\"");
        // Any finite non-zero vector is a direction (the tracer normalises it, whatever its size).
        if (r.direction == Vec3{0, 0, 0}) return bad("\"direction\" must not be the zero vector");
        out.push_back(r);
    }
    return true;
}

std::string vec3(const Vec3& v) { return fmt::format("[{}, {}, {}]", json_number(v.x), json_number(v.y), json_number(v.z)); }

int run(const TraceRaysArgs& a) {
    std::vector<InputRay> rays;
    if (!read_rays(a.rays, rays)) return 2;
    StageReport report;
    int status = 0;
    auto loaded = load_scene_and_solid(a.scene, report, status);
    if (!loaded) return status;
    TracerOptions topt;
    std::string why;
    const bool analytic_ok = Tracer::analytic_supported(loaded->solid, &why);
    if (a.representation == "analytic" && !analytic_ok) {
        std::cerr << fmt::format("ltmsim trace-rays: {}: the analytic representation {}\n", loaded->scene.source, why);
        return 2;
    }
    topt.representation = a.representation == "refined"     ? Representation::Refined
                           : a.representation == "mesh-only" ? Representation::MeshOnly
                           : (a.representation == "analytic" || analytic_ok) ? Representation::Analytic
                                                                             : Representation::Refined;
    const Tracer tracer(loaded->scene, loaded->solid, topt);
    std::string out;
    for (const auto& r : rays) {
        const PrincipalPath p = tracer.principal_path(r.origin, r.direction);
        std::string verts = "[", names = "[";
        for (size_t i = 0; i < p.vertices.size(); ++i) {
            verts += (i ? ", " : "") + vec3(p.vertices[i]);
            names += (i ? ", " : "") + json_string(loaded->solid.surfaces[p.tags[i]].name);
        }
        verts += "]";
        names += "]";
        const std::string hit = p.display_hit ? fmt::format("[{}, {}]", json_number(p.x), json_number(p.y)) : "null";
        const std::string pix = p.display_hit ? fmt::format("[{}, {}]", p.p, p.q) : "null";
        out += fmt::format("{{\"vertices\": {}, \"surfaces\": {}, \"direction\": {}, \"display_hit\": {}, \"display_pixel\": {}}}\n",
                           verts, names, vec3(p.direction), hit, pix);
    }
    std::cout << out << std::flush;
    return 0;
}

}  // namespace

void add_trace_rays_command(CLI::App& app) {
    auto args = std::make_shared<TraceRaysArgs>();
    CLI::App* cmd = app.add_subcommand("trace-rays", "Trace given rays' principal paths (JSON lines in, JSON lines out)");
    cmd->add_option("scene", args->scene, "Scene file (YAML)")->required();
    cmd->add_option("--rays", args->rays, "Rays: one {\"origin\": [x,y,z], \"direction\": [dx,dy,dz]} per line")->required();
    cmd->add_option("--threads", args->threads, "Threads (accepted for uniformity; rays are traced in order)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--representation", args->representation, "auto | refined | analytic | mesh-only")
        ->check(CLI::IsMember({"auto", "refined", "analytic", "mesh-only"}));
    cmd->callback([args] { run_guarded("trace-rays", [&] { return run(*args); }); });
}

}  // namespace ltm::app
